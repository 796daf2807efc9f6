"""Where a simulator tick's time goes: python benchmarks/profile/tick_profile.py [AGENTS] [MOVER]

Runs the Table 1 protocol (random valid actions, 10,000 decisions, every mechanic on, the
shipped damage models) under cProfile and sorts each function's own time into parts: pybullet
(world contacts, body moves), Embree (line of sight), compiled movement kernels, the bomb rules,
line of sight and damage (numpy and the models), the benchmark's random policy, recording, the
engine, the compiled stretches of decisions and glides (kinematic mover), the movers' Python
side, numpy's calls, and other Python glue. cProfile adds a fixed cost to every Python call, so
Python-heavy parts read larger than they are: compare the shares between runs of this script,
not with `decoy bench`'s ticks per second.
"""

from __future__ import annotations

import cProfile
import pstats
import sys
from collections import defaultdict

from decoy_cli.bench.machine import machine_line
from decoy_cli.bench.simspeed import run_agents
from decoy_cli.damage import load_damage_model
from decoy_cli.sim.setup import RunSpec
from decoy_cli.waypoints.build import builtin_graph
from decoy_cli.world.navmesh import nav_world
from decoy_cli.world.physics import PhysicsWorld

PARTS = (  # (part, substrings of "file:function"), first match wins
    ("pybullet", ("pybullet.", "getClosestPoints", "resetBasePosition", "MultiBody")),
    ("Embree line of sight", ("EmbreeScene", "occlusion.py")),
    ("movement kernels (numba)", ("collision.py", "kernels.py")),
    (
        "bomb rules",
        (
            "sim/rules.py",
            "sim/rules_config.py",
            "sim/plant_defuse.py",
            "sim/round_end.py",
            "sim/sites.py",
        ),
    ),
    ("line of sight and damage", ("sim/sight.py", "sim/combat.py", "damage/", "torch")),
    ("compiled stretches (decisions and glides)", ("quiet_play.py",)),
    ("random policy (the benchmark's)", ("random_play.py", "bench/simspeed.py:", "graph.py:")),
    ("recording", ("_record",)),
    (
        "engine (sim/engine.py and its parts, sim/schedule.py)",
        (
            "sim/engine.py",
            "sim/quiet_ticks.py",
            "sim/falls.py",
            "sim/judging.py",
            "sim/outside_changes.py",
            "sim/schedule.py",
        ),
    ),
    ("movers' Python (goals, calls)", ("sim/movement/",)),
    ("numpy calls", ("numpy", "{method '", "{built-in method numpy")),
)


def main() -> None:
    agents = int(sys.argv[1]) if len(sys.argv) > 1 else 10
    mover = sys.argv[2] if len(sys.argv) > 2 else "physics"
    graph = builtin_graph()
    model = load_damage_model("shipped")
    profile = cProfile.Profile()
    with PhysicsWorld(nav_world()) as physics:
        run_agents(physics, graph, 2, 200, model, RunSpec(mover=mover))  # warm-up: compilation
        profile.enable()
        row = run_agents(physics, graph, agents, 10_000, model, RunSpec(mover=mover))
        profile.disable()
    stats = pstats.Stats(profile).stats  # type: ignore[attr-defined]
    own: dict[str, float] = defaultdict(float)
    for (file, _, function), (_, _, tottime, _, _) in stats.items():
        name = f"{file}:{function}"
        part = next((p for p, keys in PARTS if any(k in name for k in keys)), "other Python glue")
        own[part] += tottime
    total = sum(own.values())
    print(machine_line())
    print(f"{agents} agents, {mover} mover: {row.ticks:,} ticks, {row.decisions:,} decisions, "
          f"{row.rounds} rounds; {total:.2f} s profiled")  # fmt: skip
    for part, seconds in sorted(own.items(), key=lambda item: -item[1]):
        print(f"  {part:<42} {seconds:6.3f} s  {seconds / total:6.1%}  "
              f"{seconds / row.ticks * 1e6:7.1f} us/tick")  # fmt: skip


if __name__ == "__main__":
    main()
