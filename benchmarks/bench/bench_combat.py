"""Cost of one combat step on the real de_dust2 world: line of sight, batch, model, damage.

Run: python benchmarks/bench/bench_combat.py [--repeats N] [--seed S]

The step timing is `decoy_cli.bench.combat` (the same code as the combat-step section of
`decoy bench`, which runs 5v5 with the real damage model); this script adds 50v50.

Agents stand at random waypoints of the built-in graph (new positions every step, so every
capsule moves, as after 0.5 s of play), half T and half CT, in two layouts: spread over the
whole map, and clustered (all within 15 m of one waypoint: many visible pairs, the worst case
for the body rays). Each step is timed in its parts: `visible_pairs` (world rays for every
enemy pair, then body rays for the pairs the world lets through), `make_batch`, a trivial
damage model defined here (hit within 20 m for 27 HP), and `apply_damage`; "step" is their sum.
Times are milliseconds: median and range over the repeats.
"""

from __future__ import annotations

import argparse
import importlib.metadata
import os
import platform
import statistics

import numpy as np

from decoy_cli.bench.combat import PARTS, time_steps
from decoy_cli.sim.combat import HIT_GROUPS, CombatBatch, DamageResult, LineOfSight
from decoy_cli.waypoints.build import builtin_graph
from decoy_cli.world.navmesh import nav_world
from decoy_cli.world.physics import PhysicsWorld


def trivial_model(batch: CombatBatch, rng: np.random.Generator) -> DamageResult:
    """Every attacker within 20 m hits the chest for 27 HP."""
    hit = batch.distance <= 20.0
    group = HIT_GROUPS.index("Chest")
    return DamageResult(np.where(hit, 27, 0), np.where(hit, group, -1), hit)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=300, help="timed steps per 5v5 case")
    parser.add_argument("--seed", type=int, default=0, help="seed of the agent placements")
    args = parser.parse_args()
    rng = np.random.default_rng(args.seed)
    world = nav_world()
    graph = builtin_graph()
    print(
        f"python {platform.python_version()}, numpy {np.__version__}, pybullet "
        f"{importlib.metadata.version('pybullet')}, {os.cpu_count()} CPUs; world {world.name} "
        f"({world.num_triangles:,} triangles), graph {graph.num_nodes:,} waypoints"
    )
    header = f"{'case':<22} {'part':<14} {'steps':>6} {'median ms':>10} {'min ms':>9} {'max ms':>9}"
    print(header)
    with PhysicsWorld(world) as physics:
        for per_side, repeats in ((5, args.repeats), (50, max(args.repeats // 10, 5))):
            los = LineOfSight(physics, 2 * per_side)
            for clustered in (False, True):
                time_steps(los, graph, trivial_model, per_side, clustered, 3, rng)  # warm-up
                times, visible = time_steps(
                    los, graph, trivial_model, per_side, clustered, repeats, rng
                )
                case = f"{per_side}v{per_side} {'clustered' if clustered else 'spread'}"
                for part in PARTS:
                    ms = [t * 1e3 for t in times[part]]
                    print(
                        f"{case:<22} {part:<14} {repeats:>6} {statistics.median(ms):>10.4f} "
                        f"{min(ms):>9.4f} {max(ms):>9.4f}"
                    )
                print(
                    f"{case:<22} {per_side * per_side} world rays per step; visible ordered "
                    f"pairs: median {statistics.median(visible):g}, range "
                    f"{min(visible)}-{max(visible)}"
                )
            los.close()


if __name__ == "__main__":
    main()
