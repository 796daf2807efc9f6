"""The cost of one combat step on the de_dust2 world: line of sight, batch, model, damage.

Agents stand at random waypoints of the built-in graph (new positions every step, so every
capsule moves, as after 0.5 s of play), half T and half CT, in two layouts: spread over the
whole map, and clustered (all within 15 m of one waypoint: many visible pairs, the worst case
for the body rays). Each step is timed in its parts: `visible_pairs` (world rays for every
enemy pair, then body rays for the pairs the world lets through), `make_batch`, the damage
model, and `apply_damage`; "step" is their sum.
"""

from __future__ import annotations

import statistics
import time

import numpy as np

from decoy_cli.bench.records import CombatRow, StepTimes
from decoy_cli.csgo import BUILTIN_MAP
from decoy_cli.sim.combat import DamageModel, LineOfSight, apply_damage, make_batch
from decoy_cli.sim.state import Agents
from decoy_cli.waypoints.build import builtin_graph
from decoy_cli.waypoints.graph import WaypointGraph
from decoy_cli.world.navmesh import nav_world
from decoy_cli.world.physics import PhysicsWorld

CLUSTER_M = 15.0
PARTS = ("visible_pairs", "make_batch", "model", "apply_damage", "step")
LAYOUTS = ("spread", "clustered")


def random_agents(
    graph: WaypointGraph, per_side: int, clustered: bool, rng: np.random.Generator
) -> Agents:
    """2 * per_side agents at distinct random waypoints, T first, rifles, random yaws."""
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
    model: DamageModel,
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
        batch = make_batch(agents, pairs, str(graph.meta.get("map", BUILTIN_MAP)))
        t2 = time.perf_counter()
        result = model(batch, rng)
        t3 = time.perf_counter()
        apply_damage(agents, batch, result, 30)
        t4 = time.perf_counter()
        for part, seconds in zip(PARTS, (t1 - t0, t2 - t1, t3 - t2, t4 - t3, t4 - t0), strict=True):
            times[part].append(seconds)
        visible.append(len(pairs))
    return times, visible


def summarize_ms(times: list[float]) -> StepTimes:
    """Median, mean, min and max of wall times in seconds, as milliseconds."""
    ms = [t * 1e3 for t in times]
    return {
        "median_ms": statistics.median(ms),
        "mean_ms": statistics.fmean(ms),
        "min_ms": min(ms),
        "max_ms": max(ms),
    }


def step_costs(
    model: DamageModel,
    per_side: int = 5,
    repeats: int = 300,
    seed: int = 0,
    map_name: str = BUILTIN_MAP,
) -> list[CombatRow]:
    """One row per layout: the step's parts (milliseconds) and the visible pairs per step, on a
    built-in map."""
    rng = np.random.default_rng(seed)
    graph = builtin_graph(map_name)
    rows: list[CombatRow] = []
    with PhysicsWorld(nav_world(map_name)) as physics:
        los = LineOfSight(physics, 2 * per_side)
        try:
            for layout in LAYOUTS:
                clustered = layout == "clustered"
                time_steps(los, graph, model, per_side, clustered, 3, rng)  # warm-up
                times, visible = time_steps(los, graph, model, per_side, clustered, repeats, rng)
                rows.append(
                    {
                        "agents": 2 * per_side,
                        "layout": layout,
                        "steps": repeats,
                        "parts": {part: summarize_ms(times[part]) for part in PARTS},
                        "visible_pairs_median": float(statistics.median(visible)),
                        "visible_pairs_max": int(max(visible)),
                    }
                )
        finally:
            los.close()
    return rows
