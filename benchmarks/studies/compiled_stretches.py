"""What the compiled stretches give: the kinematic core with and without them, side by side.

    python benchmarks/studies/compiled_stretches.py [REPEATS]

Runs the Table 1 protocol at 10 agents with the kinematic mover (10,000 decisions, every
mechanic on, the shipped models) alternately with `RandomPolicy`, which plays quiet stretches
in compiled code (`decoy_cli.sim.quiet_play`), and with the same policy behind a wrapper that
only offers `decide`, so the engine asks it one agent at a time in Python. Both play the same
rounds (`tests/test_random_play.py`); the ratio of their ticks per second, pair by pair, is what
the compiled stretches are worth.
"""

from __future__ import annotations

import sys

import numpy as np

import decoy_cli.bench.simspeed as simspeed
from decoy_cli.bench.machine import machine_line
from decoy_cli.damage import load_damage_model
from decoy_cli.sim.engine import Decision, Simulator
from decoy_cli.sim.random_play import RandomPolicy
from decoy_cli.sim.setup import RunSpec
from decoy_cli.waypoints.build import builtin_graph
from decoy_cli.world.navmesh import nav_world
from decoy_cli.world.physics import PhysicsWorld


class OneAtATime:
    """`RandomPolicy` without its compiled stretches."""

    def __init__(self, rng: np.random.Generator) -> None:
        self.policy = RandomPolicy(rng)

    def decide(self, sim: Simulator, agent: int) -> Decision:
        return self.policy.decide(sim, agent)


def main() -> None:
    repeats = int(sys.argv[1]) if len(sys.argv) > 1 else 5
    graph = builtin_graph()
    model = load_damage_model("shipped")
    print(machine_line())
    ratios = []
    kinematic = RunSpec(mover="kinematic")
    with PhysicsWorld(nav_world()) as physics:
        simspeed.run_agents(physics, graph, 2, 200, model, kinematic)  # compilation
        for _ in range(repeats):
            speed = {}
            for name, policy in (("compiled", RandomPolicy), ("one at a time", OneAtATime)):
                simspeed.RandomPolicy = policy  # type: ignore[misc, assignment]
                row = simspeed.run_agents(physics, graph, 10, 10_000, model, kinematic)
                speed[name] = row.ticks_per_s
            simspeed.RandomPolicy = RandomPolicy  # type: ignore[misc]
            ratios.append(speed["compiled"] / speed["one at a time"])
            print(f"compiled {speed['compiled']:,.0f} ticks/s, one at a time "
                  f"{speed['one at a time']:,.0f} ticks/s: {ratios[-1]:.2f}x")  # fmt: skip
    print(f"ratio median {np.median(ratios):.2f}x (min {min(ratios):.2f}, max {max(ratios):.2f})")


if __name__ == "__main__":
    main()
