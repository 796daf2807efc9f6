"""Table 1 with the first version's random policy: how much of a speed-up is the engine's.

    python benchmarks/studies/engine_only_speed.py [AGENTS ...]          # this code
    PYTHONPATH=/path/to/other/tree python benchmarks/studies/engine_only_speed.py 10 100

`decoy bench`'s random policy draws uniform numbers in blocks and reuses its decisions; the
first version's drew each action with `Generator.choice` over the mask, which costs more than a
whole tick of today's engine at 10 agents. This script runs the Table 1 protocol (10,000
decisions, every mechanic on, the shipped models, physics mover) with that per-decision policy
on whichever code it imports, so two trees run alternately on one machine give the engine's own
ratio.
"""

from __future__ import annotations

import sys

import numpy as np

import decoy_cli.bench.simspeed as simspeed
from decoy_cli.bench.machine import machine_line
from decoy_cli.damage import load_damage_model
from decoy_cli.sim.engine import Decision
from decoy_cli.waypoints.build import builtin_graph
from decoy_cli.waypoints.graph import STOP_ACTION
from decoy_cli.world.navmesh import nav_world
from decoy_cli.world.physics import PhysicsWorld


class ChoicePolicy:
    """A random valid action per decision, drawn with Generator.choice over the mask."""

    def __init__(self, rng: np.random.Generator) -> None:
        self.rng = rng

    def decide(self, sim, agent: int) -> Decision:
        mask = sim.graph.action_mask(int(sim.agents.node[agent]))
        action = int(self.rng.choice(np.flatnonzero(mask)))
        return Decision(action, hold_ticks=30, plant=action == STOP_ACTION)


def main() -> None:
    counts = [int(a) for a in sys.argv[1:]] or [10, 100]
    simspeed.RandomPolicy = ChoicePolicy  # type: ignore[misc, assignment]
    graph = builtin_graph()
    model = load_damage_model("shipped")
    print(machine_line(), "code:", simspeed.__file__)
    with PhysicsWorld(nav_world()) as physics:
        simspeed.run_agents(physics, graph, 2, 200, model)  # warm-up: compilation
        for count in counts:
            row = simspeed.run_agents(physics, graph, count, 10_000, model)
            print(f"{count} agents: {row.ticks_per_s:,.0f} ticks/s ({row.ticks:,} ticks)")


if __name__ == "__main__":
    main()
