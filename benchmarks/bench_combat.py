"""Cost of one combat step on the real de_dust2 world: line of sight, batch, model, damage.

Run: python benchmarks/bench_combat.py [--repeats N] [--seed S]

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
import time

import numpy as np

from decoy_cli.sim.combat import (
    HIT_GROUPS,
    CombatBatch,
    DamageResult,
    LineOfSight,
    apply_damage,
    make_batch,
)
from decoy_cli.sim.state import Agents
from decoy_cli.waypoints.build import builtin_graph
from decoy_cli.waypoints.graph import WaypointGraph
from decoy_cli.world.navmesh import nav_world
from decoy_cli.world.physics import PhysicsWorld

CLUSTER_M = 15.0
PARTS = ("visible_pairs", "make_batch", "model", "apply_damage", "step")


def trivial_model(batch: CombatBatch, rng: np.random.Generator) -> DamageResult:
    """Every attacker within 20 m hits the chest for 27 HP."""
    hit = batch.distance <= 20.0
    group = HIT_GROUPS.index("Chest")
    return DamageResult(np.where(hit, 27, 0), np.where(hit, group, -1), hit)


def random_agents(
    graph: WaypointGraph, per_side: int, clustered: bool, rng: np.random.Generator
) -> Agents:
    """2 * per_side agents at distinct random waypoints, T first, random yaws."""
    if clustered:
        centre = graph.positions[rng.integers(graph.num_nodes)]
        near = np.flatnonzero(np.linalg.norm(graph.positions - centre, axis=1) <= CLUSTER_M)
        pool = near if len(near) >= 2 * per_side else np.arange(graph.num_nodes)
    else:
        pool = np.arange(graph.num_nodes)
    nodes = rng.choice(pool, size=2 * per_side, replace=False)
    return Agents.create(
        [f"p{k}" for k in range(2 * per_side)],
        ["T"] * per_side + ["CT"] * per_side,
        graph.positions[nodes],
        nodes,
        weapons=["AK-47"] * per_side + ["M4A4"] * per_side,
        yaw=rng.uniform(-180.0, 180.0, 2 * per_side),
    )


def time_steps(
    los: LineOfSight,
    graph: WaypointGraph,
    per_side: int,
    clustered: bool,
    repeats: int,
    rng: np.random.Generator,
) -> tuple[dict[str, list[float]], list[int]]:
    """Per-part wall times (seconds) of `repeats` steps, and the visible ordered pairs of each."""
    times: dict[str, list[float]] = {part: [] for part in PARTS}
    visible = []
    for _ in range(repeats):
        agents = random_agents(graph, per_side, clustered, rng)
        t0 = time.perf_counter()
        pairs = los.visible_pairs(agents)
        t1 = time.perf_counter()
        batch = make_batch(agents, pairs, "de_dust2")
        t2 = time.perf_counter()
        result = trivial_model(batch, rng)
        t3 = time.perf_counter()
        apply_damage(agents, batch, result, 30)
        t4 = time.perf_counter()
        for part, seconds in zip(PARTS, (t1 - t0, t2 - t1, t3 - t2, t4 - t3, t4 - t0), strict=True):
            times[part].append(seconds)
        visible.append(len(pairs))
    return times, visible


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
                time_steps(los, graph, per_side, clustered, 3, rng)  # warm-up
                times, visible = time_steps(los, graph, per_side, clustered, repeats, rng)
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
