"""Synthetic rounds that take one edge of each kind of a map's waypoint graph (not real data).

A lone T walks a few waypoints, takes one step, jump, drop or ladder edge, and walks on, moving
as a CS:GO player does rather than as the simulator's movers do, so a replay of the round
measures how well the movers and the planner follow real motion over that kind of edge:

* walk and step edges: straight, at the player's running speed;
* a jump up: off the ground at the jump's take-off speed (more for a crouch-jump onto a higher
  edge) under sv_gravity, running on meanwhile; the edge ends when he is over its end at its
  height;
* off a ledge (a drop, a jump down): he keeps running while he falls; the edge ends when he has
  landed and is over its end;
* a ladder: straight, at the climbing speed.

Frames are sampled from that motion at a fixed rate, in the ESTA shape (`decoy_cli.esta.writer`),
so `decoy evaluate` and `replay_round` read them like any match file. Drops with fall damage
are left out (the player would lose HP the frames do not show). `benchmarks/studies/edge_kinds.py`
reports every map; the tests replay a sample.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from decoy_cli.csgo import GRAVITY_M_S2, JUMP_SPEED_M_S, LADDER_SPEED_M_S, TICK_RATE
from decoy_cli.esta.records import EstaRoundRecord, MatchRecord, PlayerRecord
from decoy_cli.waypoints.graph import EdgeKind, WaypointGraph

KINDS = (EdgeKind.STEP, EdgeKind.JUMP, EdgeKind.DROP, EdgeKind.LADDER)
"""The kinds of edge a round is made for (walk edges lead to and from each)."""
WALK_AROUND = 5
"""Waypoints walked before and after the edge."""
FREEZE_END_TICK = 1_000
ROUND_TICKS = 10_000
"""Ticks between the starts of consecutive rounds of a match."""

Motion = tuple[float, Callable[[float], np.ndarray]]
"""(seconds an edge takes, position at a time since its start)."""


def edge_motion(start: np.ndarray, end: np.ndarray, kind: int, speed: float) -> Motion:
    """How a player crosses one edge from `start` to `end` (metres) running at `speed`."""
    delta = end - start
    across = float(np.hypot(delta[0], delta[1]))
    if kind == EdgeKind.LADDER or kind not in (EdgeKind.JUMP, EdgeKind.DROP):
        rate = LADDER_SPEED_M_S if kind == EdgeKind.LADDER else speed
        took = float(np.linalg.norm(delta)) / rate
        return took, lambda t: start + delta * min(t / took, 1.0) if took > 0 else end
    rise = max(float(delta[2]), 0.0)
    take_off = max(JUMP_SPEED_M_S, float(np.sqrt(2 * GRAVITY_M_S2 * rise))) if rise > 0 else 0.0
    disc = float(np.sqrt(max(take_off**2 - 2 * GRAVITY_M_S2 * float(delta[2]), 0.0)))
    # up: the first time at the end's height; down: the landing
    air = (take_off - disc) / GRAVITY_M_S2 if rise > 0 else (take_off + disc) / GRAVITY_M_S2
    took = max(across / speed, air)

    def at(t: float) -> np.ndarray:
        share = min(t * speed / across, 1.0) if across > 0 else 1.0
        flight = min(t, air)
        z = start[2] + take_off * flight - GRAVITY_M_S2 * flight**2 / 2 if t < air else end[2]
        return np.array([start[0] + delta[0] * share, start[1] + delta[1] * share, z])

    return took, at


def edge_path(graph: WaypointGraph, edge: int, rng: np.random.Generator) -> list[int]:
    """Edges of a round over `edge`: walk edges into its start, the edge, walk edges on."""
    before = _walk(graph, int(graph.edge_source[edge]), rng, forward=False)
    return [*before[::-1], edge, *_walk(graph, int(graph.edge_target[edge]), rng, forward=True)]


def _walk(graph: WaypointGraph, node: int, rng: np.random.Generator, forward: bool) -> list[int]:
    """Up to `WALK_AROUND` walk edges on from `node` (or into it), never back to a waypoint."""
    here, there = graph.edge_source, graph.edge_target
    if not forward:
        here, there = there, here
    walks = graph.edge_kind == EdgeKind.WALK
    seen, edges = {node}, []
    for _ in range(WALK_AROUND):
        choices = [e for e in np.flatnonzero(walks & (here == node)) if int(there[e]) not in seen]
        if not choices:
            break
        edges.append(int(rng.choice(choices)))
        node = int(there[edges[-1]])
        seen.add(node)
    return edges


def path_positions(
    graph: WaypointGraph, edges: list[int], speed: float, rate: float
) -> tuple[np.ndarray, np.ndarray]:
    """(seconds, positions) of a player moving along `edges`, sampled `rate` times a second,
    and once more half a second after he arrives."""
    source, target = graph.positions[graph.edge_source], graph.positions[graph.edge_target]
    motions = [edge_motion(source[e], target[e], int(graph.edge_kind[e]), speed) for e in edges]
    ends = np.cumsum([took for took, _ in motions])
    seconds = np.append(np.arange(0.0, ends[-1], 1.0 / rate), ends[-1] + 0.5)
    positions = []
    for t in seconds:
        k = min(int(np.searchsorted(ends, t, side="right")), len(motions) - 1)
        positions.append(motions[k][1](min(t, ends[k]) - (ends[k - 1] if k else 0.0)))
    return seconds, np.array(positions)


def edge_round(
    graph: WaypointGraph, edge: int, round_num: int, rng: np.random.Generator, speed: float,
    rate: float,
) -> EstaRoundRecord:  # fmt: skip
    """One round of a lone T over `edge` (see the module docstring)."""
    seconds, positions = path_positions(graph, edge_path(graph, edge, rng), speed, rate)
    start = round_num * ROUND_TICKS
    ticks = start + FREEZE_END_TICK + np.round(seconds * TICK_RATE).astype(np.int64)
    frames = len(ticks)
    return EstaRoundRecord(
        round_num=round_num,
        start_tick=start,
        freeze_end_tick=start + FREEZE_END_TICK,
        end_tick=int(ticks[-1]) + TICK_RATE,
        end_official_tick=int(ticks[-1]) + 2 * TICK_RATE,
        frame_ticks=ticks,
        players=[PlayerRecord(name="runner", steam_id=None, side="T", inventory=("Knife",))],
        position=positions[None],
        yaw=np.zeros((1, frames)),
        hp=np.full((1, frames), 100),
        armor=np.zeros((1, frames), dtype=int),
        helmet=np.zeros((1, frames), dtype=bool),
        has_defuser=np.zeros((1, frames), dtype=bool),
        weapon=np.full((1, frames), "Knife"),
        alive=np.ones((1, frames), dtype=bool),
        has_bomb=np.zeros((1, frames), dtype=bool),
        bomb_position=np.full((frames, 3), np.nan),
        bomb_planted=np.zeros(frames, dtype=bool),
        bombsite=np.full(frames, ""),
        winning_side="CT",
        end_reason="TargetSaved",
    )


def edge_match(
    graph: WaypointGraph, per_kind: int, seed: int, speed: float, rate: float
) -> tuple[MatchRecord, list[EdgeKind]]:
    """Up to `per_kind` rounds per kind of edge the graph has (drops without fall damage), and
    the kind of each round."""
    rng = np.random.default_rng(seed)
    rounds: list[EstaRoundRecord] = []
    kinds: list[EdgeKind] = []
    for kind in KINDS:
        edges = np.flatnonzero((graph.edge_kind == kind) & (graph.fall_m == 0))
        for edge in rng.choice(edges, min(per_kind, len(edges)), replace=False):
            rounds.append(edge_round(graph, int(edge), len(rounds) + 1, rng, speed, rate))
            kinds.append(kind)
    map_name = str(graph.meta.get("map", ""))
    match = MatchRecord(
        match_id=f"edges-{map_name}-seed{seed}",
        map_name=map_name,
        tick_rate=TICK_RATE,
        rounds=rounds,
        team_names={"T": "runners", "CT": "nobody"},
        provenance={"synthetic": True, "made_by": "decoy_cli.synth.edge_rounds", "seed": seed},
    )
    return match, kinds
