"""A replayed round as the view page draws it: every player's real and replayed path, thinned,
and the round's events from the data and from the replay.

Times are integer centiseconds on the round's clock (seconds since freeze-time end), positions
integer decimetres. A path is a list of segments (the frames a player is alive and present in
a row); a segment keeps the frames that linear interpolation between its neighbours would miss
by more than `THIN_M`, each frame as (t, x, y, z) written as its difference from the frame
kept before it (the first one as it is), which keeps the page's numbers short, then the
heading at that frame in `HEADING_STEP` steps (0 = +x, counter-clockwise, -1 not known), as
it is. HP and the weapon in hand change seldom: they are kept as their changes only.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

import msgspec
import numpy as np

from decoy_cli.compiled import njit_cached

if TYPE_CHECKING:
    from decoy_cli.esta import Round
    from decoy_cli.replay.replayer import ReplayResult

THIN_M = 0.25
"""Largest distance (metres) between a thinned path and the frames it leaves out."""

CS = 100
"""Centiseconds per second."""
DM = 10
"""Decimetres per metre."""

HEADING_STEP = 10
"""Degrees per step of a kept heading (the page draws it as a short tick)."""
ROW = 5
"""Integers per kept frame of a segment: t, x, y, z (differences), heading."""

DATA = "data"
REPLAY = "replay"


class PlayerTrace(msgspec.Struct, frozen=True):
    """One player's paths (see the module docstring) and the frame of the largest error."""

    name: str
    side: str
    original: list[list[int]]
    replay: list[list[int]]
    worst_s: float | None
    """When the distance between the real and the replayed position was largest (both alive;
    None when never both alive)."""
    worst_m: float | None
    hp_original: list[int] = []
    """The data's HP where it changes: [t (centiseconds), hp, t, hp, ...] (-1: not known)."""
    hp_replay: list[int] = []
    """The replay's HP where it changes, as `hp_original`."""
    weapon: list[int] = []
    """The data's weapon in hand where it changes: [t, index in `RoundTrace.weapons` (-1:
    none), ...]; the replay holds the data's weapon."""


class RoundEvent(msgspec.Struct, frozen=True, array_like=True):
    """Something that happened in the data or in the replay: `kind` is "kill" (player: the
    attacker, -1 unknown; other: the victim), "carry" (the bomb's carrier from then on),
    "drop", "plant", "defuse" or "explode"; (x, y) where, in decimetres (None: not known);
    `inferred` the rule that filled in a data event the data does not record (None: recorded,
    or the replay's)."""

    t: int
    source: str
    kind: str
    player: int
    other: int
    x: int | None
    y: int | None
    inferred: str | None = None


class RoundTrace(msgspec.Struct, frozen=True):
    """What the round player of the view page needs of one round."""

    map_name: str
    start: int
    end: int
    """The first and last data frame (centiseconds)."""
    players: list[PlayerTrace]
    events: list[RoundEvent]
    utility: list[list[int | str]] = []
    """The data's smokes and fires with a window: [start, end (centiseconds), "smoke" or
    "fire", x, y, radius (decimetres)], drawn while active (decoy_cli/sim/utility.py's
    sizes)."""
    weapons: list[str] = []
    """The names of the weapons `PlayerTrace.weapon` indexes."""


def thin(times: np.ndarray, points: np.ndarray, tolerance: float = THIN_M) -> np.ndarray:
    """Indices of the frames to keep so that linear interpolation in time between kept frames
    is within `tolerance` of every frame left out (the first and last are always kept)."""
    n = len(times)
    if n <= 2:
        return np.arange(n)
    keep = _thin(np.asarray(times, np.float64), np.asarray(points, np.float64), float(tolerance))
    return np.flatnonzero(keep)


@njit_cached
def _thin(times, points, tolerance):
    """`thin`'s greedy sweep, compiled: a player standing still for long makes the window from
    the last kept frame long, and each step checks every frame in it."""
    n = times.shape[0]
    keep = np.zeros(n, np.bool_)
    keep[0] = True
    keep[n - 1] = True
    anchor = 0
    for end in range(2, n):
        span = max(times[end] - times[anchor], 1e-9)
        for k in range(anchor + 1, end):
            share = (times[k] - times[anchor]) / span
            error = 0.0
            for d in range(points.shape[1]):
                guess = points[anchor, d] + share * (points[end, d] - points[anchor, d])
                error += (points[k, d] - guess) ** 2
            if error > tolerance * tolerance:
                anchor = end - 1
                keep[anchor] = True
                break
    return keep


def encode_path(
    seconds: np.ndarray, position: np.ndarray, shown: np.ndarray, yaw: np.ndarray | None = None
) -> list[list[int]]:
    """The segments of one path (module docstring): frames where `shown`, thinned; `yaw` the
    heading (degrees) at each frame (None: not known)."""
    segments = []
    frames = np.flatnonzero(shown & np.isfinite(position).all(axis=1))
    if not len(frames):
        return []
    heading = headings(np.full(len(seconds), np.nan) if yaw is None else yaw)
    breaks = np.flatnonzero(np.diff(frames) > 1) + 1
    for run in np.split(frames, breaks):
        kept = run[thin(seconds[run], position[run])]
        rows = np.column_stack([np.rint(seconds[kept] * CS), np.rint(position[kept] * DM)]).astype(
            np.int64
        )
        rows[1:] -= rows[:-1].copy()
        segments.append(np.column_stack([rows, heading[kept]]).reshape(-1).tolist())
    return segments


def headings(yaw: np.ndarray) -> np.ndarray:
    """Headings in degrees as int64 `HEADING_STEP` steps in [0, 360 / step), -1 where not
    finite."""
    yaw = np.asarray(yaw, np.float64)
    finite = np.isfinite(yaw)
    steps = 360 // HEADING_STEP
    out = np.full(len(yaw), -1, np.int64)
    out[finite] = np.rint(np.mod(yaw[finite], 360.0) / HEADING_STEP).astype(np.int64) % steps
    return out


def decode_path(segment: list[int]) -> np.ndarray:
    """(K, 5) t (s), x, y, z (m), heading (degrees; NaN not known) of an encoded segment."""
    rows = np.asarray(segment, np.int64).reshape(-1, ROW)
    out = np.cumsum(rows[:, :4], axis=0).astype(np.float64) / np.array([CS, DM, DM, DM])
    heading = np.where(rows[:, 4] >= 0, rows[:, 4] * float(HEADING_STEP), np.nan)
    return np.column_stack([out, heading])


def changes(seconds: np.ndarray, values: np.ndarray) -> list[int]:
    """[t (centiseconds), value, ...] at the first frame and at each frame whose integer value
    differs from the one before it."""
    values = np.asarray(values, np.int64)
    if not len(values):
        return []
    at = np.flatnonzero(np.r_[True, values[1:] != values[:-1]])
    pairs = np.column_stack([np.rint(np.asarray(seconds)[at] * CS).astype(np.int64), values[at]])
    return pairs.reshape(-1).tolist()


def round_trace(round_: Round, result: ReplayResult) -> RoundTrace:
    """The `RoundTrace` of a replayed round."""
    from decoy_cli.replay.deaths import replay_deaths

    seconds = np.asarray(round_.frame_seconds, np.float64)
    original = np.asarray(round_.position, np.float64)  # (P, F, 3)
    present = np.asarray(round_.present, bool)
    alive_o = np.asarray(round_.alive, bool) & present
    rec = result.recording
    replayed = rec.position.transpose(1, 0, 2)
    alive_r = rec.alive.T & present
    hp_o = np.where(alive_o, np.asarray(round_.hp, np.int64), 0)
    hp_r = np.where(alive_r, rec.hp.T.astype(np.int64), 0)
    yaw_o = np.asarray(round_.yaw, np.float64)
    yaw_r = rec.yaw.T
    held = np.where(alive_o, np.asarray(round_.weapon).astype(str), "")
    weapons = sorted({w for w in held.reshape(-1).tolist() if w})
    index = {w: i for i, w in enumerate(weapons)} | {"": -1}
    players = []
    for p, info in enumerate(result.plan.players):
        both = np.flatnonzero(alive_o[p] & alive_r[p] & np.isfinite(original[p]).all(axis=1))
        worst_s = worst_m = None
        if len(both):
            error = np.linalg.norm(original[p, both] - replayed[p, both], axis=1)
            worst = int(np.argmax(error))
            worst_s, worst_m = float(seconds[both[worst]]), float(error[worst])
        players.append(
            PlayerTrace(
                name=info.name,
                side=info.side,
                original=encode_path(seconds, original[p], alive_o[p], yaw_o[p]),
                replay=encode_path(seconds, replayed[p], alive_r[p], yaw_r[p]),
                worst_s=worst_s,
                worst_m=worst_m,
                hp_original=changes(seconds, hp_o[p]),
                hp_replay=changes(seconds, hp_r[p]),
                weapon=changes(seconds, np.array([index[w] for w in held[p].tolist()])),
            )
        )
    events = _kills(DATA, result.data_deaths.seconds, result.data_deaths.killer, seconds, original)
    replay_died = replay_deaths(result.events, len(players))
    events += _kills(REPLAY, replay_died.seconds, replay_died.killer, seconds, replayed)
    events += _marked(_data_bomb(round_, result, seconds, original), result.inferred)
    events += _replay_bomb(result, seconds)
    events.sort(key=lambda e: (e.t, e.source, e.kind))
    start, end = (round(float(seconds[i]) * CS) for i in (0, -1)) if len(seconds) else (0, 0)
    return RoundTrace(
        round_.map_name, start, end, players, events, _utility(round_), weapons=weapons
    )


def _utility(round_: Round) -> list[list[int | str]]:
    """The round's smokes and fires as `RoundTrace.utility` rows."""
    from decoy_cli.sim.utility import FIRE_RADIUS_M, SMOKE_RADIUS_M

    rows: list[list[int | str]] = []
    for kind, table, radius in (
        ("smoke", round_.smokes, SMOKE_RADIUS_M),
        ("fire", round_.fires, FIRE_RADIUS_M),
    ):
        whole = table[np.isfinite(table["start_s"]) & np.isfinite(table["end_s"])]
        for row in whole.itertuples():
            rows.append(
                [
                    round(row.start_s * CS),
                    round(row.end_s * CS),
                    kind,
                    round(row.x_m * DM),
                    round(row.y_m * DM),
                    round(radius * DM),
                ]
            )
    return rows


INFERRED_BY = {
    "carry": "bomb carrier and planter",
    "plant": "bomb carrier and planter",
    "defuse": "defuse",
}
"""The filled field (replay/missing.py's notes begin with it) a data event of each kind comes
from when the data does not record it."""


def _marked(events: list[RoundEvent], notes: tuple[str, ...]) -> list[RoundEvent]:
    """The data's bomb events, each the replay filled in by a rule marked with that rule."""
    out = []
    for event in events:
        field = INFERRED_BY.get(event.kind)
        rule = next((n for n in notes if field and n.startswith(field + " (")), None)
        out.append(msgspec.structs.replace(event, inferred=rule) if rule else event)
    return out


def _event(t: float, source: str, kind: str, player: int, other: int, where: object) -> RoundEvent:
    x, y = (np.asarray(where, np.float64).reshape(-1)[:2] * DM).tolist()
    known = math.isfinite(x) and math.isfinite(y)
    at = (round(x), round(y)) if known else (None, None)
    return RoundEvent(round(float(t) * CS), source, kind, int(player), int(other), *at)


def _last_position(positions: np.ndarray, seconds: np.ndarray, t: float) -> np.ndarray:
    """A player's last finite position at or before `t` (NaN when none)."""
    finite = np.flatnonzero(np.isfinite(positions).all(axis=1) & (seconds <= t + 1e-6))
    return positions[finite[-1]] if len(finite) else np.full(3, np.nan)


def _kills(
    source: str, died: np.ndarray, killer: np.ndarray, seconds: np.ndarray, paths: np.ndarray
) -> list[RoundEvent]:
    return [
        _event(t, source, "kill", int(killer[p]), p, _last_position(paths[p], seconds, t))
        for p, t in enumerate(np.asarray(died, np.float64))
        if np.isfinite(t)
    ]


def _data_bomb(
    round_: Round, result: ReplayResult, seconds: np.ndarray, original: np.ndarray
) -> list[RoundEvent]:
    bomb = result.bomb
    if bomb is None or not bomb.recorded:
        return []
    events = []
    previous = -1
    for f, carrier in enumerate(bomb.carriers.tolist()):
        if carrier >= 0 and carrier != previous:
            events.append(_event(seconds[f], DATA, "carry", carrier, -1, original[carrier, f]))
        if bomb.drops[f]:
            where = round_.bomb_position[f]
            if not np.isfinite(where).all() and previous >= 0:
                where = original[previous, max(f - 1, 0)]
            events.append(_event(seconds[f], DATA, "drop", previous, -1, where))
        previous = carrier
    if bomb.plant is not None:
        planted = np.flatnonzero(np.asarray(round_.bomb_planted, bool))
        where = round_.bomb_position[planted[0]] if len(planted) else np.full(3, np.nan)
        if not np.isfinite(where).all() and bomb.plant.planter >= 0:
            where = _last_position(original[bomb.plant.planter], seconds, bomb.plant.seconds)
        events.append(_event(bomb.plant.seconds, DATA, "plant", bomb.plant.planter, -1, where))
    defused = bomb.defused
    if defused is not None and np.isfinite(defused.end_s):
        where = _last_position(original[defused.agent], seconds, defused.end_s)
        events.append(_event(defused.end_s, DATA, "defuse", defused.agent, -1, where))
    return events


_REPLAY_BOMB = {"bomb_pickup": "carry", "bomb_drop": "drop", "plant": "plant", "defuse": "defuse"}


def _replay_bomb(result: ReplayResult, seconds: np.ndarray) -> list[RoundEvent]:
    from decoy_cli.csgo import TICK_RATE

    if result.bomb is None:
        return []
    rec = result.recording
    events = []
    first = int(result.bomb.carriers[0]) if len(result.bomb.carriers) else -1
    if first >= 0 and rec.alive.shape[0] and rec.alive[0, first]:
        events.append(_event(seconds[0], REPLAY, "carry", first, -1, rec.position[0, first]))
    positions = rec.position.transpose(1, 0, 2)
    planted_at: object = [np.nan, np.nan]
    for e in result.events:
        t = e.tick / TICK_RATE
        if e.kind in _REPLAY_BOMB:
            where = e.data.get("position")
            if where is None:
                where = _last_position(positions[e.agent], seconds, t)
            events.append(_event(t, REPLAY, _REPLAY_BOMB[e.kind], e.agent, -1, where))
            planted_at = where if e.kind == "plant" else planted_at
        elif e.kind == "explode":
            events.append(_event(t, REPLAY, "explode", -1, -1, planted_at))
    return events
