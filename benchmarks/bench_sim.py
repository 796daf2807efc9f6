"""Simulator speed, as in the DECOY paper's Table 1: physics ticks per second by agent count.

    python benchmarks/bench_sim.py [--mover physics] [--decisions 10000] [--json out.json]

Agents (half T, half CT) start at random waypoints of their spawns and take random valid
actions (STOP holds 0.5 s) until 10,000 agent decisions have been made, headless, with the bomb
rules on and the combat step on: batched line of sight between all alive enemy pairs every 30
ticks. No learned damage model exists yet (its own issue), so the combat step here runs line of
sight and batch building with a model that never hits: the cost of damage-model inference is not
in these numbers. Rounds that end are restarted until the decision count is reached.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import time
from pathlib import Path

import numpy as np

from decoy_cli.sim.combat import CombatBatch, CombatStep, DamageResult, LineOfSight
from decoy_cli.sim.engine import Decision, SimConfig, Simulator
from decoy_cli.sim.movement import KinematicMover, PhysicsMover
from decoy_cli.sim.rules import BombRules, RulesConfig, SiteZones
from decoy_cli.sim.state import Agents
from decoy_cli.waypoints.build import builtin_graph
from decoy_cli.waypoints.graph import STOP_ACTION
from decoy_cli.world.navmesh import nav_world
from decoy_cli.world.physics import PhysicsWorld

PAPER_TICKS_PER_S = {2: 4322.0, 6: None, 10: 966.0, 20: 487.0, 100: 99.6}


class NeverHits:
    """Benchmark-only model: no pair is hit (measures line of sight, not inference)."""

    def __call__(self, batch: CombatBatch, rng: np.random.Generator) -> DamageResult:
        k = len(batch)
        return DamageResult(np.zeros(k, np.int64), np.full(k, -1, np.int8), np.zeros(k, bool))


class RandomPolicy:
    def __init__(self, rng: np.random.Generator) -> None:
        self.rng = rng

    def decide(self, sim: Simulator, agent: int) -> Decision:
        mask = sim.graph.action_mask(int(sim.agents.node[agent]))
        action = int(self.rng.choice(np.flatnonzero(mask)))
        return Decision(action, hold_ticks=30, plant=action == STOP_ACTION)


def run(count: int, mover_kind: str, decisions: int, seed: int) -> dict:
    graph = builtin_graph()
    rng = np.random.default_rng(seed)
    zones = SiteZones.from_graph(graph)
    ticks = 0
    rounds = 0
    made = 0
    game_seconds = 0.0
    with PhysicsWorld(nav_world()) as physics:
        los = LineOfSight(physics, count)
        started = time.perf_counter()
        while made < decisions:
            n_t = count // 2
            t_nodes = rng.choice(graph.region_of("t_spawn"), n_t, replace=False)
            ct_nodes = rng.choice(graph.region_of("ct_spawn"), count - n_t, replace=False)
            nodes = np.concatenate([t_nodes, ct_nodes])
            agents = Agents.create(
                names=[f"t_{i}" for i in range(n_t)] + [f"ct_{i}" for i in range(count - n_t)],
                sides=["T"] * n_t + ["CT"] * (count - n_t),
                positions=graph.positions[nodes],
                nodes=nodes,
                weapons=["AK-47"] * n_t + ["M4A4"] * (count - n_t),
            )
            mover = PhysicsMover(physics) if mover_kind == "physics" else KinematicMover()
            sim = Simulator(
                graph,
                agents,
                mover,
                RandomPolicy(rng),
                BombRules(zones, RulesConfig()),
                bomb_carrier=0,
                combat=CombatStep(los, NeverHits(), "de_dust2"),
                config=SimConfig(combat=True),
                seed=int(rng.integers(1 << 31)),
            )
            start_tick = sim.tick
            left = decisions - made
            sim.run(until=lambda s, left=left: int(s.decisions.sum()) >= left)
            made += int(sim.decisions.sum())
            ticks += sim.tick - start_tick
            game_seconds += (sim.tick - start_tick) / 60.0
            rounds += 1
            if hasattr(mover, "close"):
                mover.close()
        wall = time.perf_counter() - started
    return {
        "agents": count,
        "mover": mover_kind,
        "rounds": rounds,
        "ticks": ticks,
        "decisions": made,
        "wall_s": wall,
        "game_s": game_seconds,
        "ticks_per_s": ticks / wall,
        "time_scale": game_seconds / wall,
        "paper_ticks_per_s": PAPER_TICKS_PER_S.get(count),
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--mover", default="physics", choices=("physics", "kinematic"))
    parser.add_argument("--decisions", type=int, default=10_000)
    parser.add_argument("--agents", type=int, nargs="*", default=[2, 6, 10, 20, 100])
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--json", type=Path, default=None)
    args = parser.parse_args()
    print(f"machine: {os.cpu_count()} cores, {platform.processor() or platform.machine()}")
    run(2, args.mover, 200, args.seed)  # warm-up: numba compilation, world build
    header = "agents  ticks  decisions  wall s  game s  ticks/s  time scale  paper ticks/s  ratio"
    print(header)
    rows = []
    for count in args.agents:
        row = run(count, args.mover, args.decisions, args.seed)
        rows.append(row)
        paper = row["paper_ticks_per_s"]
        ratio = f"{row['ticks_per_s'] / paper:6.1f}x" if paper else "     -"
        print(
            f"{count:>6} {row['ticks']:>6} {row['decisions']:>10} {row['wall_s']:>7.2f} "
            f"{row['game_s']:>7.1f} {row['ticks_per_s']:>8.0f} {row['time_scale']:>11.1f} "
            f"{paper if paper else '-':>14} {ratio}"
        )
    if args.json:
        args.json.parent.mkdir(parents=True, exist_ok=True)
        args.json.write_text(json.dumps(rows, indent=2) + "\n")


if __name__ == "__main__":
    main()
