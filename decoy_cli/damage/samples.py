"""Training samples for DIP and DOG from ESTA rounds, built as the paper builds them.

A sample is one ordered (attacker, victim) pair of enemies at one 0.5 s step: the state of both
players (as a `CombatBatch` row, the input of `decoy_cli.damage.features.encode`), whether the
attacker damaged the victim in that step (DIP's label) and, for a damaging pair, how much and
where (DOG's targets). Every sample carries its group, "MATCH rROUND", so that a split never puts
one round (or, by match, one match) on both sides; see `split_samples`.

Which damage counts (both modes): firearm damage between enemies. Left out, with the reason
counted in `SampleStats.excluded`: world damage (no attacker), friendly fire, grenade, fire and
bomb damage (weaponClass "Grenade" or hitGroup "Generic"), weapons outside the models'
vocabulary (`features.WEAPONS`: knife, Zeus, C4) and rows without a damage value or hit group.

Damage value: `hpDamage` (the raw HP damage of the hit, before the victim's remaining HP caps
it), summed over the hits of one pair in one step and capped at 100. Not `hpDamageTaken`: that
is capped by the victim's remaining HP, which is not a model input, so a DOG trained on it
would learn that an AK-47 chest hit does 20 HP whenever victims happened to be low. The
simulator applies DOG's damage capped at the victim's HP (decoy_cli/damage/combat.py), which
gives back exactly ESTA's hpDamageTaken; above 100 every value kills anyone, so the cap loses
nothing and keeps the target in [0, 1] HP/100. (The paper sums raw hpDamage without the cap.)
Hit group: the six groups of `HIT_GROUPS` (Left/RightArm -> Arm, Left/RightLeg -> Leg); for a
pair hit several times in one step, the group of its largest hit (the first such on a tie).

Two modes, chosen per round ("auto": frames of both teams present -> frames, else events):

* frames (the paper's): per frame, every ordered pair of alive, present enemies with a position,
  a view yaw and a firearm of the vocabulary in hand (the simulator never asks DIP about other
  attackers). Damage events are aligned to the frame nearest their tick (the reader's
  `frame_index`) and summed per (frame, attacker, victim): label 1 for those pairs, 0 for the
  others. When the nearest frame no longer shows both players alive (a lethal hit aligned to the
  frame after the kill), the hit goes to the frame before, where both were alive. A pair-frame
  that got only excluded damage (a grenade, a knife) is dropped, neither positive nor negative.
* events (for files without frames, such as `esta_dust2_events`): there are no frames, so a 2 Hz
  grid of virtual frames (every tick_rate / 2 ticks from the round's start tick, as ESTA's frames)
  stands in. Positives are the damage events, grouped per (virtual frame, attacker, victim) like
  frames mode; the state is the one written in the group's first event row. Negatives, an honest
  proxy: at the virtual frame of every damage, kill, flash and bomb event, each player seen in an
  event row (damage, kill, flash: attacker or victim/flashed player) within `window_s` seconds
  stands where its nearest such row puts it (position and view yaw); every ordered enemy pair of
  such players, both alive, whose attacker has a known firearm and dealt the victim no damage of
  any kind within the window, is a negative (by direction, as frames mode labels ordered pairs: a
  player who was shot and missed back is a negative attacker). Bomb events carry no view yaw: they
  give anchor times, not states. The attacker's weapon is the firearm of its nearest-in-time damage
  or kill row of the round (a player who never hits or kills with a firearm in the round is never
  an attacker). HP is 100 minus the player's hpDamageTaken in the round before the tick. Armor and
  helmet, not in events, are inferred per round and player: armor if any hit on the player removed
  armor; helmet if a head hit removed armor, no helmet if a head hit removed none, else helmet =
  armor; a player never hit counts as armored with a helmet. The biases of this proxy are stated in
  models/DIP_CARD.md.
"""

from __future__ import annotations

import math
from collections import Counter
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pandas as pd

from decoy_cli.damage.features import WEAPONS, Features, FeatureSpec, encode
from decoy_cli.errors import DecoyError
from decoy_cli.esta import Round, iter_match_files, read_match
from decoy_cli.sim.combat import NO_HIT, CombatBatch

MODES = ("auto", "frames", "events")
SPLITS = ("match", "round")

DEFAULT_WINDOW_S = 2.0
"""Events-only mode: how far (seconds) an event row places a player, and how long an attacker
must have dealt its victim no damage for the pair to be a negative."""

MAX_DAMAGE_HP = 100.0
"""DOG's damage target is capped here (module docstring)."""

_HIT_GROUP_CODE = {
    "Head": 0,
    "Neck": 1,
    "Chest": 2,
    "Stomach": 3,
    "LeftArm": 4,
    "RightArm": 4,
    "Arm": 4,
    "LeftLeg": 5,
    "RightLeg": 5,
    "Leg": 5,
}

_VOCABULARY = frozenset(WEAPONS)


@dataclass(frozen=True, eq=False)
class Samples:
    """K samples: the pair state (metres, degrees), the labels and the group of each.

    `damage` is HP (0 for a negative), `hit_group` a code into HIT_GROUPS (-1 for a negative),
    `group` "MATCH rROUND", `match` the match id, `tick` the step's tick, `mode` "frames" or
    "events" (how the sample's round was read).
    """

    map_name: np.ndarray  # (K,) str
    attacker_position: np.ndarray  # (K, 3) float64 metres
    victim_position: np.ndarray  # (K, 3) float64 metres
    attacker_yaw: np.ndarray  # (K,) float64 degrees
    victim_yaw: np.ndarray  # (K,) float64 degrees
    attacker_hp: np.ndarray  # (K,) int16
    victim_hp: np.ndarray  # (K,) int16
    attacker_weapon: np.ndarray  # (K,) str
    victim_armor: np.ndarray  # (K,) int16
    victim_helmet: np.ndarray  # (K,) bool
    hit: np.ndarray  # (K,) bool
    damage: np.ndarray  # (K,) float32 HP
    hit_group: np.ndarray  # (K,) int8
    group: np.ndarray  # (K,) str
    match: np.ndarray  # (K,) str
    tick: np.ndarray  # (K,) int64
    mode: np.ndarray  # (K,) str

    def __len__(self) -> int:
        return len(self.hit)

    def take(self, index: np.ndarray | slice) -> Samples:
        """The samples at `index` (integer indices, a boolean mask or a slice)."""
        return Samples(**{name: getattr(self, name)[index] for name in _FIELDS})

    @staticmethod
    def concat(parts: Sequence[Samples]) -> Samples:
        """All samples of the parts, in order."""
        if not parts:
            return _empty_samples()
        return Samples(
            **{name: np.concatenate([getattr(p, name) for p in parts]) for name in _FIELDS}
        )

    def batch(self, index: np.ndarray | None = None) -> CombatBatch:
        """The samples (all, or those at `index`, which must share one map) as a CombatBatch;
        attacker and victim indices are the sample numbers."""
        rows = np.arange(len(self)) if index is None else np.asarray(index)
        maps = np.unique(self.map_name[rows])
        if len(maps) > 1:
            raise ValueError(f"a CombatBatch holds one map, these samples hold {len(maps)}")
        a, v = self.attacker_position[rows], self.victim_position[rows]
        delta = v - a
        ahead = np.arctan2(delta[:, 1], delta[:, 0]) - np.radians(self.attacker_yaw[rows])
        bearing = np.where(
            np.hypot(delta[:, 0], delta[:, 1]) > 0, (ahead + np.pi) % (2 * np.pi) - np.pi, 0.0
        )
        return CombatBatch(
            attacker=rows.astype(np.int64),
            victim=rows.astype(np.int64),
            attacker_position=a,
            victim_position=v,
            attacker_yaw=self.attacker_yaw[rows],
            victim_yaw=self.victim_yaw[rows],
            attacker_hp=self.attacker_hp[rows],
            victim_hp=self.victim_hp[rows],
            attacker_weapon=self.attacker_weapon[rows],
            victim_armor=self.victim_armor[rows],
            victim_helmet=self.victim_helmet[rows],
            distance=np.linalg.norm(delta, axis=1),
            bearing=bearing,
            map_name=str(maps[0]) if len(maps) else "de_dust2",
        )

    def features(self, spec: FeatureSpec) -> Features:
        """The model inputs of every sample, encoded one map at a time by `encode`."""
        if len(self) == 0:
            return encode(self.batch(), spec)
        parts: list[Features] = []
        order: list[np.ndarray] = []
        for name in np.unique(self.map_name):
            rows = np.flatnonzero(self.map_name == name)
            parts.append(encode(self.batch(rows), spec))
            order.append(rows)
        features = Features.concat(parts)
        back = np.empty(len(self), dtype=np.int64)
        back[np.concatenate(order)] = np.arange(len(self))
        return features.take(back)


_FIELDS = tuple(Samples.__dataclass_fields__)


def _empty_samples() -> Samples:
    return Samples(
        map_name=np.zeros(0, dtype=object),
        attacker_position=np.zeros((0, 3)),
        victim_position=np.zeros((0, 3)),
        attacker_yaw=np.zeros(0),
        victim_yaw=np.zeros(0),
        attacker_hp=np.zeros(0, np.int16),
        victim_hp=np.zeros(0, np.int16),
        attacker_weapon=np.zeros(0, dtype=object),
        victim_armor=np.zeros(0, np.int16),
        victim_helmet=np.zeros(0, bool),
        hit=np.zeros(0, bool),
        damage=np.zeros(0, np.float32),
        hit_group=np.zeros(0, np.int8),
        group=np.zeros(0, dtype=object),
        match=np.zeros(0, dtype=object),
        tick=np.zeros(0, np.int64),
        mode=np.zeros(0, dtype=object),
    )


@dataclass
class SampleStats:
    """What building the samples used and left out."""

    files: int = 0
    rounds_frames: int = 0
    rounds_events: int = 0
    rounds_without_samples: int = 0
    round_errors: int = 0
    excluded: Counter[str] = field(default_factory=Counter)
    realigned: int = 0
    positives: int = 0
    negatives: int = 0

    def to_json(self) -> dict[str, object]:
        """The counts as a JSON-ready dict."""
        return {
            "files": self.files,
            "rounds_frames": self.rounds_frames,
            "rounds_events": self.rounds_events,
            "rounds_without_samples": self.rounds_without_samples,
            "round_errors": self.round_errors,
            "excluded_damage_rows": dict(sorted(self.excluded.items())),
            "realigned_hits": self.realigned,
            "positives": self.positives,
            "negatives": self.negatives,
        }


def build_samples(
    data: Sequence[str | Path],
    mode: str = "auto",
    window_s: float = DEFAULT_WINDOW_S,
    on_file: Callable[[Path, int, int], None] | None = None,
) -> tuple[Samples, SampleStats]:
    """Samples from ESTA match files or folders of them (module docstring).

    `on_file(path, done, total)` is called after each file. Rounds the reader rejects are
    skipped and counted. No usable sample at all is a DecoyError.
    """
    if mode not in MODES:
        raise DecoyError(f"mode must be one of {', '.join(MODES)}, not {mode!r}")
    if not (math.isfinite(window_s) and window_s > 0):
        raise DecoyError(f"the event window must be a positive number of seconds, not {window_s}")
    files: list[Path] = []
    for item in data:
        files.extend(iter_match_files(item))
    if not files:
        raise DecoyError("no data given: pass ESTA match files or folders")
    stats = SampleStats(files=len(files))
    parts: list[Samples] = []
    for done, path in enumerate(files, start=1):
        match = read_match(path)
        stats.round_errors += len(match.round_errors)
        for round_ in match.rounds:
            part = round_samples(round_, mode, window_s, stats)
            if part is None or len(part) == 0:
                stats.rounds_without_samples += 1
                continue
            parts.append(part)
        if on_file is not None:
            on_file(path, done, len(files))
    samples = Samples.concat(parts)
    stats.positives = int(samples.hit.sum())
    stats.negatives = len(samples) - stats.positives
    if len(samples) == 0:
        names = ", ".join(str(d) for d in data)
        raise DecoyError(
            f"{names}: no usable samples ({stats.files} files; rounds need frames of both "
            "teams or firearm damage events between enemies)"
        )
    return samples, stats


def has_both_teams(round_: Round) -> bool:
    """True when the round's frames hold players of both sides (frames mode is possible)."""
    sides = {p.side for p in round_.players}
    return round_.num_frames > 0 and sides == {"T", "CT"}


def round_samples(round_: Round, mode: str, window_s: float, stats: SampleStats) -> Samples | None:
    """The samples of one round in the given mode ("auto" picks per round); None when the mode
    cannot read it (forced frames without both teams' frames)."""
    use_frames = has_both_teams(round_) if mode == "auto" else mode == "frames"
    if use_frames:
        if not has_both_teams(round_):
            return None
        stats.rounds_frames += 1
        return _frame_samples(round_, stats)
    stats.rounds_events += 1
    return _event_samples(round_, window_s, stats)


# ---- damage rows ------------------------------------------------------------------------------


def _keys(table: pd.DataFrame, owner: str) -> np.ndarray:
    """(N,) object array of player keys (steamID string, else name; None when unknown)."""
    ids = table[f"{owner}SteamID"].to_numpy(dtype=object, na_value=None)
    names = table[f"{owner}Name"].to_numpy(dtype=object, na_value=None)
    out = np.empty(len(table), dtype=object)
    for i, (steam_id, name) in enumerate(zip(ids, names, strict=True)):
        if steam_id is not None and int(steam_id) != 0:
            out[i] = str(int(steam_id))
        elif isinstance(name, str) and name:
            out[i] = name
        else:
            out[i] = None
    return out


def _strings(table: pd.DataFrame, column: str) -> np.ndarray:
    """A string column as an object array with "" for nulls."""
    values = table[column].to_numpy(dtype=object, na_value=None)
    return np.array([v if isinstance(v, str) else "" for v in values], dtype=object)


def _ints(table: pd.DataFrame, column: str) -> np.ndarray:
    """A nullable integer column as float64 with NaN for nulls."""
    return table[column].to_numpy(dtype=np.float64, na_value=np.nan)


@dataclass(frozen=True)
class _Damages:
    """The damage rows of a round with what sample building needs, and which rows are usable."""

    tick: np.ndarray  # float64, NaN when null
    attacker: np.ndarray  # object keys or None
    victim: np.ndarray
    weapon: np.ndarray
    hp_damage: np.ndarray  # float64
    hp_taken: np.ndarray  # float64 (NaN -> 0 when summed)
    armor_damage: np.ndarray  # float64
    group_code: np.ndarray  # int64, -1 when none
    usable: np.ndarray  # bool


def _damages(round_: Round, stats: SampleStats) -> _Damages:
    """Classify every damage row (module docstring) and count the reasons for leaving one out."""
    table = round_.damages
    attacker = _keys(table, "attacker")
    victim = _keys(table, "victim")
    weapon = _strings(table, "weapon")
    weapon_class = _strings(table, "weaponClass")
    hit_group = _strings(table, "hitGroup")
    attacker_side = _strings(table, "attackerSide")
    victim_side = _strings(table, "victimSide")
    friendly = table["isFriendlyFire"].to_numpy(dtype=object, na_value=None)
    hp_damage = _ints(table, "hpDamage")
    tick = _ints(table, "tick")
    group_code = np.array([_HIT_GROUP_CODE.get(g, -1) for g in hit_group], dtype=np.int64)
    usable = np.zeros(len(table), dtype=bool)
    for i in range(len(table)):
        if attacker[i] is None or weapon[i] == "World":
            reason = "world damage (no attacker)"
        elif friendly[i] is True or (attacker_side[i] and attacker_side[i] == victim_side[i]):
            reason = "friendly fire"
        elif weapon_class[i] == "Grenade" or hit_group[i] == "Generic":
            reason = "grenade, fire or bomb"
        elif weapon[i] not in _VOCABULARY:
            reason = "weapon outside the vocabulary"
        elif group_code[i] < 0:
            reason = "unknown hit group"
        elif not (hp_damage[i] > 0) or victim[i] is None or not np.isfinite(tick[i]):
            reason = "no damage value, victim or tick"
        else:
            usable[i] = True
            continue
        stats.excluded[reason] += 1
    return _Damages(
        tick=tick,
        attacker=attacker,
        victim=victim,
        weapon=weapon,
        hp_damage=hp_damage,
        hp_taken=np.nan_to_num(_ints(table, "hpDamageTaken")),
        armor_damage=np.nan_to_num(_ints(table, "armorDamage")),
        group_code=group_code,
        usable=usable,
    )


def _aggregate(
    step: np.ndarray, attacker: np.ndarray, victim: np.ndarray, damages: _Damages, rows: np.ndarray
) -> dict[tuple[int, object, object], tuple[float, int, int]]:
    """Per (step, attacker, victim): (summed hpDamage capped at 100, hit group of the largest
    hit, the first row), over the damage rows `rows` (in row order)."""
    out: dict[tuple[int, object, object], tuple[float, int, int]] = {}
    largest: dict[tuple[int, object, object], float] = {}
    for r in rows:
        key = (int(step[r]), attacker[r], victim[r])
        value = float(damages.hp_damage[r])
        if key not in out:
            out[key] = (value, int(damages.group_code[r]), int(r))
            largest[key] = value
            continue
        total, group, first = out[key]
        if value > largest[key]:
            largest[key] = value
            group = int(damages.group_code[r])
        out[key] = (total + value, group, first)
    return {k: (min(v[0], MAX_DAMAGE_HP), v[1], v[2]) for k, v in out.items()}


def _group_id(round_: Round) -> str:
    return f"{round_.match_id} r{round_.round_num}"


# ---- frames mode ------------------------------------------------------------------------------


def _frame_samples(round_: Round, stats: SampleStats) -> Samples:
    """Frames mode (module docstring)."""
    damages = _damages(round_, stats)
    row_of = {p.key: i for i, p in enumerate(round_.players)}
    side = np.array([p.side for p in round_.players])
    players, frames = len(round_.players), round_.num_frames
    valid = (
        round_.present
        & round_.alive
        & (round_.hp > 0)
        & np.isfinite(round_.position).all(axis=2)
        & np.isfinite(round_.yaw)
    )
    armed = np.isin(round_.weapon, list(_VOCABULARY))

    def code(f: np.ndarray, a: np.ndarray, v: np.ndarray) -> np.ndarray:
        """One integer per (frame, attacker row, victim row)."""
        return (np.asarray(f, np.int64) * players + a) * players + v

    frame_index = round_.damages["frame_index"].to_numpy()
    a_row = np.array([row_of.get(k, -1) if k is not None else -1 for k in damages.attacker], int)
    v_row = np.array([row_of.get(k, -1) if k is not None else -1 for k in damages.victim], int)
    placed = (a_row >= 0) & (v_row >= 0) & (frame_index >= 0)
    unplaced = int((damages.usable & ~placed).sum())
    if unplaced:
        stats.excluded["players not in the frames"] += unplaced
    step = frame_index.copy()
    for r in np.flatnonzero(placed & damages.usable):
        f, a, v = step[r], a_row[r], v_row[r]
        if not (valid[a, f] and valid[v, f]) and f > 0 and valid[a, f - 1] and valid[v, f - 1]:
            step[r] = f - 1
            stats.realigned += 1
    hits = _aggregate(step, a_row, v_row, damages, np.flatnonzero(damages.usable & placed))
    other = np.flatnonzero(placed & ~damages.usable)
    ambiguous = code(step[other], a_row[other], v_row[other])

    t_rows, ct_rows = np.flatnonzero(side == "T"), np.flatnonzero(side == "CT")
    one, two = np.meshgrid(t_rows, ct_rows, indexing="ij")
    pair_a = np.concatenate([one.ravel(), two.ravel()])
    pair_v = np.concatenate([two.ravel(), one.ravel()])
    f_idx = np.repeat(np.arange(frames), len(pair_a))
    a = np.tile(pair_a, frames)
    v = np.tile(pair_v, frames)
    hit_keys = list(hits)
    hit_codes = code(
        np.array([h[0] for h in hit_keys], np.int64),
        np.array([h[1] for h in hit_keys], np.int64),
        np.array([h[2] for h in hit_keys], np.int64),
    )
    codes = code(f_idx, a, v)
    is_hit = np.isin(codes, hit_codes)
    keep = valid[a, f_idx] & valid[v, f_idx] & (armed[a, f_idx] | is_hit)
    keep &= ~np.isin(codes, ambiguous) | is_hit
    f_idx, a, v, codes = f_idx[keep], a[keep], v[keep], codes[keep]
    k = len(f_idx)
    hit = np.zeros(k, dtype=bool)
    damage = np.zeros(k, dtype=np.float32)
    group = np.full(k, NO_HIT, dtype=np.int8)
    weapon = round_.weapon[a, f_idx].astype(object)
    position_of = {int(c): i for i, c in enumerate(codes)}
    for key, hit_code in zip(hit_keys, hit_codes, strict=True):
        i = position_of.get(int(hit_code))
        if i is None:
            stats.excluded["hit on a pair not alive in its frame"] += 1
            continue
        total, hit_group, first = hits[key]
        hit[i], damage[i], group[i] = True, total, hit_group
        weapon[i] = damages.weapon[first]  # the gun that fired, not the one in hand at the frame
    return Samples(
        map_name=np.full(k, round_.map_name, dtype=object),
        attacker_position=round_.position[a, f_idx],
        victim_position=round_.position[v, f_idx],
        attacker_yaw=round_.yaw[a, f_idx],
        victim_yaw=round_.yaw[v, f_idx],
        attacker_hp=round_.hp[a, f_idx].astype(np.int16),
        victim_hp=round_.hp[v, f_idx].astype(np.int16),
        attacker_weapon=weapon,
        victim_armor=round_.armor[v, f_idx].astype(np.int16),
        victim_helmet=round_.helmet[v, f_idx].astype(bool),
        hit=hit,
        damage=damage,
        hit_group=group,
        group=np.full(k, _group_id(round_), dtype=object),
        match=np.full(k, round_.match_id, dtype=object),
        tick=round_.frame_ticks[f_idx].astype(np.int64),
        mode=np.full(k, "frames", dtype=object),
    )


# ---- events-only mode -------------------------------------------------------------------------


@dataclass(frozen=True)
class _Sightings:
    """Where event rows place players: tick, key, side, position (metres) and view yaw."""

    tick: np.ndarray
    key: np.ndarray
    side: np.ndarray
    position: np.ndarray
    yaw: np.ndarray


def _sightings(round_: Round) -> _Sightings:
    """Every (player, tick) an event row places with a position and a view yaw."""
    ticks, keys, sides, positions, yaws = [], [], [], [], []
    for table, owners in (
        (round_.damages, ("attacker", "victim")),
        (round_.kills, ("attacker", "victim")),
        (round_.flashes, ("attacker", "player")),
    ):
        if len(table) == 0:
            continue
        tick = _ints(table, "tick")
        for owner in owners:
            ticks.append(tick)
            keys.append(_keys(table, owner))
            sides.append(_strings(table, f"{owner}Side"))
            positions.append(
                np.column_stack([table[f"{owner}{axis}_m"].to_numpy() for axis in "XYZ"])
            )
            yaws.append(table[f"{owner}ViewX"].to_numpy(dtype=np.float64))
    if not ticks:
        empty = np.zeros(0)
        return _Sightings(empty, np.zeros(0, object), np.zeros(0, object), np.zeros((0, 3)), empty)
    tick = np.concatenate(ticks)
    key = np.concatenate(keys)
    side = np.concatenate(sides)
    position = np.concatenate(positions)
    yaw = np.concatenate(yaws)
    known = (
        np.isfinite(tick)
        & np.array([k is not None for k in key], dtype=bool)
        & np.isin(side, ["T", "CT"])
        & np.isfinite(position).all(axis=1)
        & np.isfinite(yaw)
    )
    return _Sightings(tick[known], key[known], side[known], position[known], yaw[known])


class _EventRound:
    """What the event rows of one round say about its players over time (events-only mode)."""

    def __init__(self, round_: Round, damages: _Damages) -> None:
        self.round = round_
        self.damages = damages
        self.step_ticks = max(1, round(round_.tick_rate / 2))
        self.origin = round_.start_tick if round_.start_tick is not None else 0
        kills = round_.kills
        self.kill_tick = _ints(kills, "tick")
        self.kill_victim = _keys(kills, "victim")
        ticks, keys, names = [], [], []
        for table in (round_.damages, kills):
            weapon = _strings(table, "weapon")
            armed = np.isin(weapon, list(_VOCABULARY)) & np.isfinite(_ints(table, "tick"))
            ticks.append(_ints(table, "tick")[armed])
            keys.append(_keys(table, "attacker")[armed])
            names.append(weapon[armed])
        self.weapon_tick = np.concatenate(ticks)
        self.weapon_key = np.concatenate(keys)
        self.weapon_name = np.concatenate(names)
        self.armor = self._infer_armor()

    def frame(self, ticks: np.ndarray) -> np.ndarray:
        """The virtual 2 Hz frame nearest each tick."""
        return np.rint((ticks - self.origin) / self.step_ticks).astype(np.int64)

    def frame_tick(self, frame: int) -> int:
        """The tick of a virtual frame."""
        return int(self.origin + frame * self.step_ticks)

    def hp_before(self, player: object, tick: float) -> int:
        """100 minus the player's hpDamageTaken in the round before `tick` (at least 1: the
        player is alive)."""
        rows = (self.damages.victim == player) & (self.damages.tick < tick)
        return int(max(1.0, 100.0 - float(self.damages.hp_taken[rows].sum())))

    def dead_at(self, player: object, tick: float) -> bool:
        """True when a kill row has the player die at or before `tick`."""
        return bool(np.any((self.kill_victim == player) & (self.kill_tick <= tick)))

    def weapon_at(self, player: object, tick: float) -> str | None:
        """The firearm of the player's damage or kill row nearest `tick`; None without one."""
        rows = np.flatnonzero(self.weapon_key == player)
        if len(rows) == 0:
            return None
        return str(self.weapon_name[rows[np.argmin(np.abs(self.weapon_tick[rows] - tick))]])

    def armor_of(self, player: object) -> tuple[int, bool]:
        """(armor as 100 or 0, helmet) as inferred; armored with a helmet when never hit."""
        has_armor, helmet = self.armor.get(player, (True, True))
        return (100 if has_armor else 0), helmet

    def _infer_armor(self) -> dict[object, tuple[bool, bool]]:
        """Per player hit in the round: (armor, helmet) from the armor its hits removed."""
        hit_group = _strings(self.round.damages, "hitGroup")
        out: dict[object, tuple[bool, bool]] = {}
        for player in {k for k in self.damages.victim if k is not None}:
            rows = self.damages.victim == player
            armor = bool(np.any(self.damages.armor_damage[rows] > 0))
            head = rows & (hit_group == "Head")
            helmet = bool(np.any(self.damages.armor_damage[head] > 0)) if head.any() else armor
            out[player] = (armor or helmet, helmet)
        return out


def _event_samples(round_: Round, window_s: float, stats: SampleStats) -> Samples:
    """Events-only mode (module docstring): positives from the damage rows, then negatives."""
    events = _EventRound(round_, _damages(round_, stats))
    rows: list[dict[str, object]] = []
    rows += _event_positives(events, stats)
    rows += _event_negatives(events, window_s * round_.tick_rate)
    common = {
        "map_name": round_.map_name,
        "group": _group_id(round_),
        "match": round_.match_id,
        "mode": "events",
    }
    return _from_rows([{**common, **row} for row in rows])


def _event_positives(events: _EventRound, stats: SampleStats) -> list[dict[str, object]]:
    """One sample per (virtual frame, attacker, victim) with usable damage; the state of the
    group's first damage row."""
    damages, table = events.damages, events.round.damages
    usable = np.flatnonzero(damages.usable)
    frame = events.frame(np.nan_to_num(damages.tick))
    rows = []
    for (k, attacker, victim), (total, code, first) in _aggregate(
        frame, damages.attacker, damages.victim, damages, usable
    ).items():
        a_pos = np.array([table[f"attacker{axis}_m"].iloc[first] for axis in "XYZ"])
        v_pos = np.array([table[f"victim{axis}_m"].iloc[first] for axis in "XYZ"])
        a_yaw = float(table["attackerViewX"].iloc[first])
        v_yaw = float(table["victimViewX"].iloc[first])
        if not np.isfinite([*a_pos, *v_pos, a_yaw, v_yaw]).all():
            stats.excluded["no attacker or victim state"] += 1
            continue
        tick = float(damages.tick[first])
        armor, helmet = events.armor_of(victim)
        rows.append(
            {
                "attacker_position": a_pos,
                "victim_position": v_pos,
                "attacker_yaw": a_yaw,
                "victim_yaw": v_yaw,
                "attacker_hp": events.hp_before(attacker, tick),
                "victim_hp": events.hp_before(victim, tick),
                "attacker_weapon": str(damages.weapon[first]),
                "victim_armor": armor,
                "victim_helmet": helmet,
                "hit": True,
                "damage": total,
                "hit_group": code,
                "tick": events.frame_tick(k),
            }
        )
    return rows


def _event_negatives(events: _EventRound, window: float) -> list[dict[str, object]]:
    """At the virtual frame of every damage, kill, flash and bomb event: the ordered enemy pairs
    of players seen within `window` ticks, alive, the attacker with a known firearm, and the
    attacker having dealt the victim no damage of any kind within the window."""
    round_, damages = events.round, events.damages
    sightings = _sightings(round_)
    tables = (round_.damages, round_.kills, round_.flashes, round_.bomb_events)
    ticks = np.concatenate([_ints(t, "tick") for t in tables])
    ticks = ticks[np.isfinite(ticks)]
    any_damage = np.isfinite(damages.tick) & np.array(
        [
            a is not None and v is not None
            for a, v in zip(damages.attacker, damages.victim, strict=True)
        ],
        dtype=bool,
    )
    rows = []
    for k in np.unique(events.frame(ticks)):
        anchor = float(events.frame_tick(int(k)))
        seen: dict[object, int] = {}  # per player, its sighting nearest the anchor
        distance = np.abs(sightings.tick - anchor)
        for s in np.flatnonzero(distance <= window):
            best = seen.get(sightings.key[s])
            if best is None or distance[s] < distance[best]:
                seen[sightings.key[s]] = s
        players = [p for p in seen if not events.dead_at(p, anchor)]
        near = any_damage & (np.abs(damages.tick - anchor) <= window)
        dealt = {(damages.attacker[r], damages.victim[r]) for r in np.flatnonzero(near)}
        for attacker in players:
            weapon = events.weapon_at(attacker, anchor)
            if weapon is None:
                continue
            sa = seen[attacker]
            for victim in players:
                sv = seen[victim]
                if sightings.side[sa] == sightings.side[sv] or (attacker, victim) in dealt:
                    continue
                armor, helmet = events.armor_of(victim)
                rows.append(
                    {
                        "attacker_position": sightings.position[sa],
                        "victim_position": sightings.position[sv],
                        "attacker_yaw": float(sightings.yaw[sa]),
                        "victim_yaw": float(sightings.yaw[sv]),
                        "attacker_hp": events.hp_before(attacker, anchor),
                        "victim_hp": events.hp_before(victim, anchor),
                        "attacker_weapon": weapon,
                        "victim_armor": armor,
                        "victim_helmet": helmet,
                        "hit": False,
                        "damage": 0.0,
                        "hit_group": NO_HIT,
                        "tick": int(anchor),
                    }
                )
    return rows


def _from_rows(rows: list[dict[str, object]]) -> Samples:
    """Samples from one dict of field values per sample."""
    if not rows:
        return _empty_samples()
    dtypes = {
        "attacker_position": np.float64,
        "victim_position": np.float64,
        "attacker_yaw": np.float64,
        "victim_yaw": np.float64,
        "attacker_hp": np.int16,
        "victim_hp": np.int16,
        "victim_armor": np.int16,
        "victim_helmet": bool,
        "hit": bool,
        "damage": np.float32,
        "hit_group": np.int8,
        "tick": np.int64,
    }
    return Samples(
        **{
            name: np.array([row[name] for row in rows], dtype=dtypes.get(name, object))
            for name in _FIELDS
        }
    )


# ---- split and balance ------------------------------------------------------------------------


@dataclass(frozen=True)
class Split:
    """Sample indices of the train, validation and test parts, and the groups of each."""

    train: np.ndarray
    val: np.ndarray
    test: np.ndarray
    units: dict[str, list[str]]

    def part(self, name: str) -> np.ndarray:
        """The indices of "train", "val", "test" or "all" (every index, sorted)."""
        if name == "all":
            return np.sort(np.concatenate([self.train, self.val, self.test]))
        if name not in ("train", "val", "test"):
            raise DecoyError(f"subset must be all, train, val or test, not {name!r}")
        return getattr(self, name)


def split_samples(
    samples: Samples, by: str, seed: int, val_fraction: float, test_fraction: float
) -> Split:
    """Split by match or by round (never by sample): the units, sorted, are shuffled with the
    seed; the first round(test_fraction * n) (at least 1) go to test, the next
    round(val_fraction * n) (at least 1) to validation, the rest to training."""
    if by not in SPLITS:
        raise DecoyError(f"split must be match or round, not {by!r}")
    for name, value in (("validation", val_fraction), ("test", test_fraction)):
        if not (0.0 < value < 1.0):
            raise DecoyError(f"the {name} fraction must be between 0 and 1, not {value}")
    if val_fraction + test_fraction >= 1.0:
        raise DecoyError("the validation and test fractions leave nothing to train on")
    unit_of = samples.match if by == "match" else samples.group
    units = sorted(set(unit_of.tolist()))
    n = len(units)
    n_test = max(1, round(test_fraction * n))
    n_val = max(1, round(val_fraction * n))
    if n - n_test - n_val < 1:
        what = "matches" if by == "match" else "rounds"
        hint = ": use --split round" if by == "match" else ""
        raise DecoyError(
            f"a split by {by} needs at least 3 {what} with samples, the data has {n}{hint}"
        )
    order = np.random.default_rng(seed).permutation(n)
    shuffled = [units[i] for i in order]
    parts = {
        "test": shuffled[:n_test],
        "val": shuffled[n_test : n_test + n_val],
        "train": shuffled[n_test + n_val :],
    }
    index = {
        name: np.flatnonzero(np.isin(unit_of, np.array(members, dtype=object)))
        for name, members in parts.items()
    }
    return Split(
        index["train"], index["val"], index["test"], {k: sorted(v) for k, v in parts.items()}
    )


def balance(samples: Samples, index: np.ndarray, seed: int) -> np.ndarray:
    """The indices in `index` with all positives and as many negatives, drawn with the seed (all
    negatives when there are fewer), sorted: the paper's 1:1 balanced DIP set."""
    index = np.asarray(index, dtype=np.int64)
    positive = index[samples.hit[index]]
    negative = index[~samples.hit[index]]
    if len(negative) > len(positive):
        negative = np.random.default_rng(seed).choice(negative, len(positive), replace=False)
    return np.sort(np.concatenate([positive, negative]))
