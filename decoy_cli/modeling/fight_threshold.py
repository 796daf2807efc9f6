"""The fight's operating point: the DIP threshold the combat step decides by, chosen where the
fight works, on real rounds of both teams.

DIP's own threshold is the best F1 on its validation match: pairs of players at real events,
whose attackers mostly look elsewhere. The fight meets other pairs: every pair in sight, each
attacker aimed at his enemy after a reaction time (`sim/combat.py`), where that threshold says
"hit" far more often than real players damage each other. So the fight's threshold is chosen
on what the fight meets:

* **objective**: in real rounds of both teams, every frame at which a player alive has exactly
  one enemy in sight (the nav world, eye to eye, real positions) gives a pair as the fight sees
  it, each aimed at the other, labelled by whether the player lost HP within `HORIZON_S`; the
  threshold with the best F1 of DIP's "hit" against those labels (the combat step decides every
  0.5 s, so a pair at or above it is hit about twice in such a second: the label asks whether
  the second saw damage at all, as the fight's first hit does);
* **constraint**: DIP still says "hit" on at least `MIN_RECALL` of the real damaging steps of
  every map of the events data, so that it stays a classifier of real hits: of the
  steps it did not train on (outside the training part its metadata names: its validation and
  test matches or rounds), where a map has any, since recall on its own training steps flatters
  it; a map it trained on whole is held on those, and says so.

Candidates: DIP's own threshold and `GRID`. `choose_fight_threshold` returns the table behind
the choice; `decoy models fight-threshold` writes the choice as the folder's calibration (kind
"none": the combat step decides by its threshold).
"""

from __future__ import annotations

from collections.abc import Iterable, Iterator
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from decoy_cli.damage.combat import DipDecision, armed
from decoy_cli.damage.model_folder import LoadedDip
from decoy_cli.errors import DecoyError
from decoy_cli.esta import Round, RoundFailure, collect_match_files, each_round, iter_rounds
from decoy_cli.geometry import eye_point, facing_yaw
from decoy_cli.modeling.calibration_fit import MIN_RECALL
from decoy_cli.modeling.network_evaluation import dip_probabilities
from decoy_cli.modeling.provenance import seen_in
from decoy_cli.modeling.sample_set import Samples, SampleStats
from decoy_cli.modeling.samples import (
    DEFAULT_MODE,
    DEFAULT_WINDOW_S,
    SAMPLE_ERROR,
    round_samples,
)
from decoy_cli.replay.missing import fill_missing
from decoy_cli.sim.combat import CombatBatch
from decoy_cli.sim.rules import RulesConfig
from decoy_cli.sim.sites import SiteZones
from decoy_cli.waypoints.build import graph_world
from decoy_cli.waypoints.graph import WaypointGraph
from decoy_cli.world.physics import PhysicsWorld

GRID = tuple(round(0.05 * k, 2) for k in range(1, 20))
"""Candidate thresholds besides DIP's own."""
HORIZON_S = 1.0
"""How long after a frame a lost HP counts (the 1 s frame interval of the real CS2 rounds; the
label means the same at any frame rate)."""


@dataclass(frozen=True)
class FightPairs:
    """The objective's pairs (module docstring): what DIP sees and whether the victim lost HP."""

    batch: CombatBatch
    lost_hp: np.ndarray  # (K,) bool
    round_index: np.ndarray  # (K,) int64: which of the rounds used, in their order
    rounds: int  # rounds that gave at least one pair


def fight_pairs(rounds: Iterable[Round], graph: WaypointGraph) -> FightPairs:
    """Every (frame, player) of the rounds with both teams whose player, alive with his HP known
    at the frame and the next, has exactly one enemy in sight; weapons and armour filled by
    `fill_missing`'s rules where the data lacks them."""
    zones = SiteZones.from_graph(graph)
    parts: list[tuple[Round, np.ndarray]] = []
    with PhysicsWorld(graph_world(graph)) as world:
        for round_ in rounds:
            if not (len(round_.side_indices("T")) and len(round_.side_indices("CT"))):
                continue
            filled = fill_missing(round_, zones, RulesConfig(), "infer").round
            rows = _in_sight_alone(filled, world)
            if len(rows):
                parts.append((filled, rows))
    return _pairs(parts, str(graph.meta.get("map", "")))


def enemies_in_sight(
    round_: Round, world: PhysicsWorld, watched: np.ndarray
) -> Iterator[tuple[int, int, np.ndarray]]:
    """(frame, player, the enemies in sight of him) for every frame and player `watched` (P, F)
    marks whose eye position is known: the enemies alive at the frame with a known position,
    eye to eye in `world` at the real positions, in index order (none when none is)."""
    alive = np.asarray(round_.alive, bool) & np.asarray(round_.present, bool)
    eyes = eye_point(np.asarray(round_.position, dtype=np.float64))
    side = np.array([p.side for p in round_.players])
    known = alive & np.isfinite(eyes).all(axis=2)
    for frame in range(known.shape[1]):
        for player in np.flatnonzero(watched[:, frame] & np.isfinite(eyes[:, frame]).all(axis=1)):
            enemies = np.flatnonzero(known[:, frame] & (side != side[player]))
            if not len(enemies):
                yield frame, int(player), enemies
                continue
            ends = np.repeat(eyes[player, frame][None], len(enemies), axis=0)
            yield frame, int(player), enemies[world.line_of_sight(eyes[enemies, frame], ends)]


def _in_sight_alone(round_: Round, world: PhysicsWorld) -> np.ndarray:
    """(K, 4) attacker, victim, frame, lost HP within `HORIZON_S`: the round's players with
    exactly one enemy in sight at a frame (frames without a frame `HORIZON_S` later left out)."""
    hp = np.asarray(round_.hp, dtype=np.float64)
    alive = np.asarray(round_.alive, bool) & np.asarray(round_.present, bool)
    seconds = np.asarray(round_.frame_seconds, dtype=np.float64)
    later = np.searchsorted(seconds, seconds + HORIZON_S - 1e-6)
    has_later = later < len(seconds)
    then = np.where(has_later, later, 0)
    watched = alive & has_later & (hp >= 0) & (hp[:, then] >= 0)
    rows = []
    for frame, victim, seen_by in enemies_in_sight(round_, world, watched):
        if len(seen_by) != 1:
            continue
        after = int(then[frame])
        lost = not alive[victim, after] or hp[victim, after] < hp[victim, frame]
        rows.append((int(seen_by[0]), victim, frame, int(lost)))
    return np.array(rows, dtype=np.int64).reshape(-1, 4)


def _pairs(parts: list[tuple[Round, np.ndarray]], map_name: str) -> FightPairs:
    batches: list[CombatBatch] = []
    lost: list[np.ndarray] = []
    numbers: list[np.ndarray] = []
    for round_, rows in parts:  # rounds without such a frame were left out
        attacker, victim, frame = rows[:, 0], rows[:, 1], rows[:, 2]
        position = np.asarray(round_.position, dtype=np.float64)
        at, to = position[attacker, frame], position[victim, frame]
        facing = facing_yaw(to[:, 0] - at[:, 0], to[:, 1] - at[:, 1])
        hp = np.clip(np.asarray(round_.hp)[:, frame], 1, 100).astype(np.int16)
        weapon = np.asarray(round_.weapon, dtype=object)[attacker, frame].astype(str)
        batches.append(
            CombatBatch(
                attacker=attacker,
                victim=victim,
                attacker_position=at,
                victim_position=to,
                attacker_yaw=facing,
                victim_yaw=facing + 180.0,
                attacker_hp=hp[attacker, np.arange(len(rows))],
                victim_hp=hp[victim, np.arange(len(rows))],
                attacker_weapon=weapon,
                victim_armor=np.asarray(round_.armor)[victim, frame].clip(0, 100).astype(np.int16),
                victim_helmet=np.asarray(round_.helmet, bool)[victim, frame],
                map_name=map_name,
            )
        )
        lost.append(rows[:, 3].astype(bool))
        numbers.append(np.full(len(rows), len(numbers), dtype=np.int64))
    if not batches:
        raise DecoyError(
            f"no round of {map_name or 'the map'} whose frames hold both teams has a frame with a "
            "player and exactly one enemy in sight: nothing to choose the fight's threshold on"
        )
    return FightPairs(
        CombatBatch.concat(batches),
        np.concatenate(lost),
        np.concatenate(numbers),
        len(parts),
    )


@dataclass(frozen=True)
class FightThreshold:
    """The chosen threshold and, per candidate, the objective's F1 and the recall per map."""

    threshold: float
    own_threshold: float
    rows: list[dict[str, float]]
    """candidate: threshold, f1 (objective), recall:<map> (constraint), allowed (0/1)."""


def pair_probabilities(dip: LoadedDip, pairs: FightPairs) -> np.ndarray:
    """DIP's probability for each pair; 0 where the attacker cannot hit (`combat.armed`)."""
    probability = DipDecision(dip).hit_probability(pairs.batch)
    return np.where(armed(pairs.batch), probability, 0.0)


def choose_fight_threshold(
    probability: np.ndarray,
    lost_hp: np.ndarray,
    damaging: dict[str, np.ndarray],
    own_threshold: float,
    min_recall: float = MIN_RECALL,
) -> FightThreshold:
    """The candidate with the best F1 of `probability` >= it against `lost_hp` (the objective's
    pairs) among those at which at least `min_recall` of each map's `damaging` probabilities
    (DIP's on the real damaging steps) reach it; DIP's `own_threshold`, the training's choice,
    is a candidate whatever its recall. Ties go to the lower threshold."""
    rows = []
    for threshold in sorted({*GRID, float(own_threshold)}):
        hit = probability >= threshold
        f1 = 2 * float(np.sum(hit & lost_hp)) / max(int(hit.sum() + lost_hp.sum()), 1)
        recall = {name: float(np.mean(p >= threshold)) for name, p in damaging.items()}
        allowed = threshold == own_threshold or min(recall.values()) >= min_recall
        row = {"threshold": threshold, "f1": f1, "allowed": float(allowed)}
        rows.append(row | {f"recall:{name}": value for name, value in recall.items()})
    best = max((r for r in rows if r["allowed"]), key=lambda r: (r["f1"], -r["threshold"]))
    return FightThreshold(float(best["threshold"]), float(own_threshold), rows)


def _damaging_by_map(steps: Samples, trained: np.ndarray | None) -> dict[str, Samples]:
    """Each map's damaging steps DIP did not train on, named "<map> held out (N)"; a map whose
    every step it trained on keeps them all, "<map> trained on (N)"; every step, "<map> all
    steps (N)", when which it trained on is not known. (Held-out steps include its validation
    part, which chose its epoch and its own threshold, never its weights.)"""
    out = {}
    for name in sorted(set(steps.map_name)):
        on_map = steps.map_name == name
        held = on_map if trained is None else on_map & ~trained
        label = "all steps" if trained is None else "held out"
        if not held.any():
            held, label = on_map, "trained on"
        out[f"{name} {label} ({int(held.sum())})"] = steps.take(np.flatnonzero(held))
    return out


@dataclass(frozen=True)
class FightChoice:
    """`choose_for_files`'s result: the choice on all rounds, on each half of them alone, and
    what it was made on."""

    chosen: FightThreshold
    halves: tuple[float, float]
    pairs: int
    lost_share: float
    rounds: int
    maps: tuple[str, ...]
    failures: list[RoundFailure]


def choose_for_files(
    dip: LoadedDip, paths: list[Path], graph: WaypointGraph, min_recall: float = MIN_RECALL
) -> FightChoice:
    """The fight's threshold from ESTA files or folders: the rounds of `graph`'s map whose frames
    hold both teams give the objective, the damage events of every file the constraint (module
    docstring). A DecoyError when either gives nothing to choose on."""
    files, _ = collect_match_files(paths)
    if not files:
        raise DecoyError("no data given: pass ESTA match files or folders")
    failures: list[RoundFailure] = []
    rounds: list[Round] = []
    parts: list[Samples] = []

    def damaging_steps(round_: Round) -> Samples | None:  # the samples `models evaluate` scores
        if not len(round_.damages):
            return None
        part = round_samples(round_, DEFAULT_MODE, DEFAULT_WINDOW_S, SampleStats())
        return None if part is None else part.take(np.flatnonzero(part.hit))

    for item in each_round(iter_rounds(files), damaging_steps, SAMPLE_ERROR):
        if isinstance(item, RoundFailure):
            failures.append(item)
            continue
        round_, part = item
        if round_.map_name == graph.meta.get("map"):
            rounds.append(round_)
        if part is not None and len(part):
            parts.append(part)
    pairs = fight_pairs(rounds, graph)
    if not parts:
        raise DecoyError(
            "no usable samples: the data holds no damaging step to hold DIP's recall on"
        )
    hits = Samples.concat(parts)
    damaging = _damaging_by_map(hits, seen_in(dip.metadata, hits, ("train",)))
    probability = pair_probabilities(dip, pairs)
    on_map = {name: dip_probabilities(dip, samples) for name, samples in damaging.items()}

    def choose(part: np.ndarray) -> FightThreshold:
        return choose_fight_threshold(
            probability[part], pairs.lost_hp[part], on_map, dip.threshold, min_recall
        )

    first = pairs.round_index < pairs.rounds / 2
    chosen, halves = choose(np.ones(len(first), bool)), [choose(first), choose(~first)]
    return FightChoice(
        chosen,
        (halves[0].threshold, halves[1].threshold),
        len(pairs.lost_hp),
        float(pairs.lost_hp.mean()),
        pairs.rounds,
        tuple(damaging),
        failures,
    )
