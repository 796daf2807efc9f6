"""Simulator speed as in the DECOY paper's Table 1: physics ticks per second by agent count.

Agents (half T, half CT) start at random waypoints of their spawns and take random valid actions
(a STOP holds 0.5 s) until the requested number of agent decisions, headless, with every
mechanic on: the mover, the bomb rules, and the combat step every 30 ticks (batched line of
sight between all alive enemy pairs, then the damage model on the visible pairs). Rounds that
end (time, bomb, or elimination once the model kills) are restarted with new agents until the
decision count is reached; every restart is inside the timed run, as in the paper's loop.

Without a damage model the combat step runs line of sight and batch building with `NeverHits`,
a model that never hits: its rows leave out the cost of inference and must say so.
"""

from __future__ import annotations

import time
from dataclasses import asdict, dataclass
from typing import cast

import numpy as np

from decoy_cli.bench.records import SpeedRowRecord
from decoy_cli.csgo import BUILTIN_MAP, TICK_RATE
from decoy_cli.sim.combat import CombatBatch, DamageModel, DamageResult
from decoy_cli.sim.random_play import RandomPolicy
from decoy_cli.sim.setup import MoverName, RoundSetup, RunSpec, open_round
from decoy_cli.sim.state import Agents
from decoy_cli.waypoints.build import builtin_graph
from decoy_cli.waypoints.graph import WaypointGraph
from decoy_cli.world.navmesh import nav_world
from decoy_cli.world.physics import PhysicsWorld

AGENT_COUNTS = (2, 6, 10, 20, 100)
"""The paper's Table 1 rows."""

PAPER_DECISIONS = 10_000
"""Agent decisions per row in the paper's Table 1."""

PAPER_SPEC = RunSpec(mover="physics")
"""The paper's Table 1 run: its physics mover, shooting and the bomb on."""

PAPER_TICKS_PER_S: dict[int, float | None] = {2: 4322.0, 6: None, 10: 966.0, 20: 487.0, 100: 99.6}
"""The paper's physics ticks per second by agent count (None: no value recorded here)."""


class NeverHits:
    """A damage model under which no pair is hit: the combat step without inference."""

    def __call__(self, batch: CombatBatch, rng: np.random.Generator) -> DamageResult:
        k = len(batch)
        return DamageResult(np.zeros(k, np.int64), np.full(k, -1, np.int8), np.zeros(k, bool))


@dataclass
class SpeedRow:
    """One Table 1 row: totals over the restarted rounds of one agent count."""

    agents: int
    mover: MoverName
    rounds: int
    ticks: int
    decisions: int
    kills: int
    wall_s: float
    cpu_s: float
    game_s: float
    ticks_per_s: float
    time_scale: float
    paper_ticks_per_s: float | None  # the paper's table, from its machine (not comparable)

    def to_dict(self) -> SpeedRowRecord:
        """The row as its record (`SpeedRowRecord` names the same fields)."""
        return cast(SpeedRowRecord, asdict(self))


def _spawn_agents(graph: WaypointGraph, count: int, rng: np.random.Generator) -> Agents:
    """count // 2 T at T-spawn waypoints, the rest CT at CT-spawn waypoints, rifles."""
    n_t = count // 2
    t_nodes = rng.choice(graph.region_of("t_spawn"), n_t, replace=False)
    ct_nodes = rng.choice(graph.region_of("ct_spawn"), count - n_t, replace=False)
    nodes = np.concatenate([t_nodes, ct_nodes])
    return Agents.create(
        names=[f"t_{i}" for i in range(n_t)] + [f"ct_{i}" for i in range(count - n_t)],
        sides=["T"] * n_t + ["CT"] * (count - n_t),
        positions=graph.positions[nodes],
        nodes=nodes,
        weapons=["AK-47"] * n_t + ["M4A4"] * (count - n_t),
    )


def run_agents(
    physics: PhysicsWorld,
    graph: WaypointGraph,
    count: int,
    decisions: int,
    model: DamageModel,
    spec: RunSpec = PAPER_SPEC,
) -> SpeedRow:
    """Play restarted rounds of `count` agents until `decisions` agent decisions (module doc)."""
    if count < 2:
        raise ValueError(f"a round needs at least 2 agents, not {count}")
    setup = RoundSetup(
        graph=graph, mover=spec.mover, combat=spec.combat, bomb=spec.bomb, damage_model=model
    )
    rng = np.random.default_rng(spec.seed)
    ticks = rounds = made = kills = 0
    started = time.perf_counter()
    cpu_started = time.process_time()
    while made < decisions:
        agents = _spawn_agents(graph, count, rng)
        with open_round(
            setup,
            agents,
            RandomPolicy(rng),
            physics=physics,
            bomb_carrier=0,
            seed=int(rng.integers(1 << 31)),
        ) as sim:
            start_tick = sim.tick
            sim.run(max_decisions=decisions - made)
        made += int(sim.state.decisions.sum())
        ticks += sim.tick - start_tick
        kills += int((~agents.alive).sum())
        rounds += 1
    wall = time.perf_counter() - started
    cpu = time.process_time() - cpu_started
    game = ticks / TICK_RATE
    paper = PAPER_TICKS_PER_S.get(count)
    return SpeedRow(
        agents=count,
        mover=spec.mover,
        rounds=rounds,
        ticks=ticks,
        decisions=made,
        kills=kills,
        wall_s=wall,
        cpu_s=cpu,
        game_s=game,
        ticks_per_s=ticks / wall,
        time_scale=game / wall,
        paper_ticks_per_s=paper,
    )


def speed_table(
    counts: tuple[int, ...] = AGENT_COUNTS,
    decisions: int = PAPER_DECISIONS,
    model: DamageModel | None = None,
    *,
    mover: MoverName = "physics",
    combat: bool = True,
    bomb: bool = True,
    seed: int = 0,
    warmup_decisions: int = 200,
    map_name: str = BUILTIN_MAP,
) -> list[SpeedRow]:
    """Table 1 rows for each agent count, after an untimed warm-up (compilation, caches).

    `model` None runs the combat step with `NeverHits` (line of sight, no inference); `combat`
    False runs no combat step at all. `map_name` is the built-in map played on.
    """
    graph = builtin_graph(map_name)
    model = NeverHits() if model is None else model
    spec = RunSpec(mover=mover, combat=combat, bomb=bomb, seed=seed)
    with PhysicsWorld(nav_world(map_name)) as physics:
        if warmup_decisions:
            run_agents(physics, graph, 2, warmup_decisions, model, spec)
        return [run_agents(physics, graph, n, decisions, model, spec) for n in counts]
