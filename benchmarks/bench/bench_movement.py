"""Speed of the movers: ticks per second with 2, 10, 20 and 100 agents on the real de_dust2 graph.

Agents do random walks: whenever one arrives, it takes a random out-edge of its node, at 250 u/s
(the knife speed). They start on distinct random waypoints either spread over the whole map
("spread") or, as in a round, half in the T spawn and half in the CT spawn ("spawns", crowded).
Each configuration runs `--ticks` ticks after a warm-up, `--runs` times (run k uses seed k);
reported are the median and range of the ticks per second of `step()` alone (the mover's cost)
and of the whole loop (with the walk's Python driver), the simulator's target (10x the paper's
rate), and, for the physics mover, stuck events and teleports per agent-minute and the share of
agent-ticks whose move needed a world test.

    python benchmarks/bench/bench_movement.py [--runs 5] [--ticks 3000] [--agents 2 10 20 100]
"""

from __future__ import annotations

import argparse
import os
import platform
import statistics
import time

import numpy as np

from decoy_cli.csgo import HAMMER_TO_M, TICK_RATE
from decoy_cli.sim.movement import KinematicMover, MoverBase, PhysicsMover
from decoy_cli.waypoints.build import builtin_graph
from decoy_cli.waypoints.graph import WaypointGraph
from decoy_cli.world.navmesh import nav_world
from decoy_cli.world.physics import PhysicsWorld

TARGET_TICKS_PER_S = {2: 43_220, 10: 9_660, 20: 4_870, 100: 996}
"""The whole simulator's target: ten times the DECOY paper's ticks per second."""
SPEED_M_S = 250 * HAMMER_TO_M


def start_nodes(graph: WaypointGraph, agents: int, start: str, rng: np.random.Generator):
    """Distinct random start waypoints, over the whole map or split between the two spawns."""
    if start == "spread":
        return rng.choice(graph.num_nodes, size=agents, replace=False)
    t_side = rng.choice(graph.region_of("t_spawn"), size=agents - agents // 2, replace=False)
    ct_side = rng.choice(graph.region_of("ct_spawn"), size=agents // 2, replace=False)
    return np.concatenate([t_side, ct_side])


def random_walk(
    mover: MoverBase, graph: WaypointGraph, agents: int, start: str, ticks: int, seed: int
) -> tuple[float, float, dict[str, int]]:
    """Run a random walk; (seconds in step(), seconds in total, counts)."""
    rng = np.random.default_rng(seed)
    node = start_nodes(graph, agents, start, rng)
    mover.reset(graph.positions[node])
    out_edges = graph.out_edges

    def give(a: int) -> None:
        edges = out_edges[node[a]]
        edge = int(rng.choice(edges[edges >= 0]))
        node[a] = graph.edge_target[edge]
        mover.set_goal(a, graph.positions[node[a]], int(graph.edge_kind[edge]), SPEED_M_S)

    for a in range(agents):
        give(a)
    in_step = 0.0
    arrivals = 0
    start = time.perf_counter()
    for _ in range(ticks):
        clock = time.perf_counter()
        step = mover.step()
        in_step += time.perf_counter() - clock
        for a in np.flatnonzero(step.arrived).tolist():
            arrivals += 1
            give(a)
    total = time.perf_counter() - start
    counts = {
        "arrivals": arrivals,
        "stuck": int(np.sum(mover.stuck_events)),
        "teleports": int(np.sum(mover.recoveries)),
        "world_checks": getattr(mover, "world_checks", 0),
    }
    return in_step, total, counts


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=5)
    parser.add_argument("--ticks", type=int, default=3000)
    parser.add_argument("--agents", type=int, nargs="+", default=[2, 10, 20, 100])
    parser.add_argument("--start", nargs="+", default=["spread", "spawns"])
    args = parser.parse_args()

    graph = builtin_graph()
    world = nav_world()
    print(
        f"python {platform.python_version()}, {os.cpu_count()} CPUs; de_dust2 graph: "
        f"{graph.num_nodes} nodes, {graph.num_edges} edges; {args.ticks} ticks per run, "
        f"median [min-max] of {args.runs} runs"
    )
    header = (
        f"{'mover':<10}{'start':<8}{'agents':>7}{'step() ticks/s':>28}{'loop ticks/s':>28}"
        f"{'target':>8}{'stuck/a-min':>13}{'teleports/a-min':>17}{'world tests':>13}"
    )
    print(header)
    with PhysicsWorld(world) as physics:
        movers: dict[str, MoverBase] = {
            "kinematic": KinematicMover(),
            "physics": PhysicsMover(physics),
        }
        for name, mover in movers.items():
            for start in args.start:
                for agents in args.agents:
                    random_walk(mover, graph, agents, start, 200, seed=99)  # warm-up
                    step_rates, loop_rates = [], []
                    totals = dict.fromkeys(("stuck", "teleports", "world_checks"), 0)
                    for run in range(args.runs):
                        in_step, total, counts = random_walk(
                            mover, graph, agents, start, args.ticks, run
                        )
                        step_rates.append(args.ticks / in_step)
                        loop_rates.append(args.ticks / total)
                        for key in totals:
                            totals[key] += counts[key]
                    agent_ticks = agents * args.ticks * args.runs
                    minutes = agent_ticks / TICK_RATE / 60
                    print(
                        f"{name:<10}{start:<8}{agents:>7}{fmt(step_rates):>28}"
                        f"{fmt(loop_rates):>28}{TARGET_TICKS_PER_S.get(agents, 0):>8,}"
                        f"{totals['stuck'] / minutes:>13.2f}"
                        f"{totals['teleports'] / minutes:>17.3f}"
                        f"{totals['world_checks'] / agent_ticks:>13.2%}"
                    )


def fmt(rates: list[float]) -> str:
    return f"{statistics.median(rates):,.0f} [{min(rates):,.0f}-{max(rates):,.0f}]"


if __name__ == "__main__":
    main()
