"""The frames of one round turned into per-player arrays of shape (P, F), in metres.

Players are keyed by `steamID` (as a string), falling back to `name` when the steamID is null or
0 (awpy writes 0 for bots); their order inside a frame is not trusted. A row is a player on one
side: a key seen on both sides (impossible within a round) has two rows, for the plausibility
checks to name it. Rows are ordered T first,
then CT, each by key. A player entry whose x, y or z is null cannot be placed: it counts as absent
from that frame, like a player missing from the list. Absent cells hold NaN (position, yaw),
`MISSING` (hp, armor), "" (weapon) and False (flags, `alive`, `present`). A NaN, infinite or off-map
coordinate (beyond the engine's ±16,384 Hammer units) is an error, and so is an unknown weapon.

The round's clock is the game's: seconds since freeze-time end counted in ticks at the file's
`tickRate` (`round_clock_zero`). A file's own `seconds` only place the zero: some awpy 1.x
exports wrote them at 127 per second on 128-tick demos, a clock 0.8% slow against the game's
115 s round time (benchmarks/studies/clock_study.py measures it).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

import numpy as np
import numpy.typing as npt
import pandas as pd

from decoy_cli.csgo import HAMMER_TO_M, MAX_VELOCITY_M_S
from decoy_cli.esta.schema import FrameState, Invalid, PlayerState, TeamState
from decoy_cli.weapons import is_known

Side = Literal["T", "CT"]

MAX_COORD_U = 16_384.0
"""Largest possible |coordinate| in Hammer units: the Source engine's world bound
(MAX_COORD_INTEGER). de_dust2 spans about ±3,500 u; de_vertigo's floors lie near z = 11,500 u."""

MISSING = -1
"""hp and armor where the player is absent or the value is null."""

_MAX_EXACT = 2.0**53
"""Largest integer a float64 holds exactly: ticks and ids beyond it are corrupt."""


@dataclass(frozen=True)
class PlayerInfo:
    """One player of a round: `key` is the steamID as a string, else the name."""

    key: str
    name: str
    steam_id: int | None
    side: Side


@dataclass(frozen=True)
class RoundClock:
    """The game's clock of a round: seconds since freeze-time end (`zero_tick`), in ticks at
    the server's `tick_rate`."""

    zero_tick: float
    tick_rate: int

    def seconds(self, ticks: npt.ArrayLike) -> np.ndarray:
        """Seconds on this clock at each tick."""
        return (np.asarray(ticks, dtype=np.float64) - self.zero_tick) / self.tick_rate


@dataclass(frozen=True, eq=False)
class FrameArrays:
    """Everything the frames of one round hold, as arrays (see Round for the meaning)."""

    ticks: np.ndarray
    seconds: np.ndarray
    clock: RoundClock | None
    players: list[PlayerInfo]
    position: np.ndarray
    yaw: np.ndarray
    hp: np.ndarray
    armor: np.ndarray
    helmet: np.ndarray
    has_defuser: np.ndarray
    weapon: np.ndarray
    alive: np.ndarray
    present: np.ndarray
    has_bomb: np.ndarray
    vertical_speed: np.ndarray
    bomb_position: np.ndarray
    bomb_planted: np.ndarray
    bombsite: np.ndarray


def build_frames(
    frames: list[FrameState],
    tick_rate: int,
    freeze_end_tick: int | None,
    start_tick: int | None,
) -> FrameArrays:
    """Turn one round's frames into arrays; a bad frame raises Invalid naming frame and player."""
    if len(frames) > MAX_FRAMES:
        raise Invalid(f"{len(frames):,} frames (a round holds at most {MAX_FRAMES:,})")
    ticks = _ticks(frames)
    written = np.array([f.seconds for f in frames], dtype=np.float64)
    zero_tick = round_clock_zero(written, ticks, tick_rate, freeze_end_tick, start_tick)
    clock = None if zero_tick is None else RoundClock(zero_tick, tick_rate)
    seconds = clock.seconds(ticks) if clock is not None else np.zeros(0)
    check_clock(seconds, ticks)
    _check_written_seconds(written, seconds, ticks)
    bomb_position = _bomb_position(frames, ticks)
    players, arrays = _players(frames, ticks)
    return FrameArrays(
        ticks=ticks,
        seconds=seconds,
        clock=clock,
        players=players,
        **arrays,
        bomb_position=bomb_position,
        bomb_planted=np.array([f.bombPlanted is True for f in frames], dtype=bool),
        bombsite=np.array([f.bombsite or "" for f in frames], dtype=str),
    )


def _where(ticks: np.ndarray, frame: int) -> str:
    """'frame j (tick t)' for messages."""
    return f"frame {frame} (tick {ticks[frame]})" if frame < ticks.size else f"frame {frame}"


def _ticks(frames: list[FrameState]) -> np.ndarray:
    """(F,) int64 ticks; every frame needs one, and they must not decrease."""
    raw = np.array([f.tick for f in frames], dtype=np.float64)
    with np.errstate(invalid="ignore"):
        bad = ~np.isfinite(raw) | (np.abs(raw) > _MAX_EXACT) | (raw != np.round(raw))
    if bad.any():
        j = int(np.argmax(bad))
        raise Invalid(f"frame {j} has no valid tick ({frames[j].tick!r})")
    ticks = raw.astype(np.int64)
    back = np.flatnonzero(np.diff(ticks) < 0)
    if back.size:
        j = int(back[0]) + 1
        raise Invalid(
            f"frame {j} (tick {ticks[j]}) comes before frame {j - 1} (tick {ticks[j - 1]})"
        )
    return ticks


def round_clock_zero(
    seconds: np.ndarray,
    ticks: np.ndarray,
    tick_rate: int,
    freeze_end_tick: int | None,
    start_tick: int | None,
) -> float | None:
    """The tick at which the round's clock reads 0 s (freeze-time end), None if nothing says.

    `freezeTimeEndTick` when given; else the tick the frames' written `seconds` (NaN where
    null) imply, at the rate they were written with (some awpy 1.x exports divided by 127 on
    128-tick demos); else `startTick`; else the first frame's tick.
    """
    if freeze_end_tick is not None:
        return float(freeze_end_tick)
    known = np.isfinite(seconds)
    if known.any():
        rate = float(tick_rate)
        with np.errstate(over="ignore", invalid="ignore", divide="ignore"):
            dt = np.diff(seconds[known])
            if (dt > 0).any():
                written = float(np.median(np.diff(ticks[known])[dt > 0] / dt[dt > 0]))
                if 0.5 * tick_rate <= written <= 2.0 * tick_rate:
                    rate = written
            return float(np.median(ticks[known] - seconds[known] * rate))
    if start_tick is not None:
        return float(start_tick)
    return float(ticks[0]) if ticks.size else None


MAX_ROUND_S = 600.0
"""Largest frame time accepted, seconds from freeze-time end: over three times the longest real
round measured in the data (183 s in the T-side rounds; the game's rules give 115 s of round
time plus the 40 s bomb timer), so frame times far beyond it are a broken clock, not a round."""

MAX_FRAMES = int(MAX_ROUND_S * 128)
"""Most frames a round may hold: one per tick at 128 ticks/s for `MAX_ROUND_S` (real rounds
in ../shared/data have a frame every 0.50 s, median). Bounds the memory of a hostile round."""

MAX_PLAYERS = 64
"""Most distinct players a round's frames may hold: a CS:GO server has at most 64 player slots
(a competitive round has 10; the T-side files in ../shared/data hold 5). Bounds the (players,
frames) arrays."""


def check_clock(seconds: np.ndarray, ticks: np.ndarray) -> None:
    """Frame times (non-decreasing, as the ticks are) must be finite and within `MAX_ROUND_S`
    of freeze-time end."""
    bad = ~np.isfinite(seconds) | (np.abs(seconds) > MAX_ROUND_S)
    if bad.any():
        f = int(np.flatnonzero(bad)[0])
        raise Invalid(
            f"{_where(ticks, f)}: frame time {seconds[f]:g} s is not within {MAX_ROUND_S:g} s "
            "of freeze-time end (a round lasts at most 115 s plus the 40 s bomb timer)"
        )


CLOCK_TOLERANCE = (0.02, 1.0)
"""How far a frame's written `seconds` may lie from the game clock's reading at its tick:
2% of the reading plus 1 s. The real files' `seconds` run 0.8% slow in some matches (127 per
second on 128-tick demos, benchmarks/studies/clock_study.py); farther off, the file contradicts
itself."""


def _check_written_seconds(written: np.ndarray, seconds: np.ndarray, ticks: np.ndarray) -> None:
    """The file's own `seconds` (where given) must run forwards and agree with the ticks."""
    with np.errstate(invalid="ignore", over="ignore"):
        given = np.flatnonzero(np.isfinite(written))
        back = given[1:][np.diff(written[given]) < 0]
        if len(back):
            f = int(back[0])
            raise Invalid(
                f"{_where(ticks, f)}: frame time {written[f]:g} s is before the previous frame's"
            )
        share, slack = CLOCK_TOLERANCE
        allowed = share * np.abs(seconds[given]) + slack
        off = given[np.abs(written[given] - seconds[given]) > allowed]
    if len(off):
        f = int(off[0])
        raise Invalid(
            f"{_where(ticks, f)}: frame time {written[f]:g} s disagrees with its tick "
            f"({seconds[f]:g} s on the game clock)"
        )


def _bomb_position(frames: list[FrameState], ticks: np.ndarray) -> np.ndarray:
    """(F, 3) bomb position in metres, NaN where null."""
    rows = [(b.x, b.y, b.z) if (b := f.bomb) is not None else (None, None, None) for f in frames]
    position = np.array(rows, dtype=np.float64).reshape(len(frames), 3)
    with np.errstate(invalid="ignore"):
        off = (np.abs(position) > MAX_COORD_U).any(axis=1)
    if off.any():
        j = int(np.argmax(off))
        x, y, z = position[j]
        raise Invalid(
            f"{_where(ticks, j)}: bomb position ({x:.1f}, {y:.1f}, {z:.1f}) u is off the map "
            f"(beyond ±{MAX_COORD_U:,.0f} u)"
        )
    return position * HAMMER_TO_M


def _steam_id(value: int | float, ticks: np.ndarray, frame: int) -> int | None:
    """A non-null steamID as an int; 0 (bots) gives None."""
    if isinstance(value, float):
        if not (np.isfinite(value) and value == round(value) and abs(value) < _MAX_EXACT):
            raise Invalid(f"{_where(ticks, frame)}: steamID {value!r} is not an integer")
        value = int(value)
    return value or None


@dataclass(frozen=True, eq=False)
class PlayerRows:
    """A round's player entries in long form, one row per player per frame (E rows), as any
    source gives them: what `player_arrays` validates and scatters into (P, F) arrays.

    `key` is the steamID as a string, else the name; `position` (E, 3) Hammer units, `located`
    where x, y and z are all given (not null: a NaN is an error); the other numbers float64, NaN
    where null; `alive` 1.0, 0.0 or NaN (unknown: hp > 0 decides);
    `weapon` "" where none; `vertical_speed` Hammer units per second.
    """

    frame: np.ndarray
    key: np.ndarray
    name: np.ndarray
    steam_id: np.ndarray
    side: np.ndarray
    position: np.ndarray
    located: np.ndarray
    yaw: np.ndarray
    hp: np.ndarray
    armor: np.ndarray
    helmet: np.ndarray
    has_defuser: np.ndarray
    has_bomb: np.ndarray
    alive: np.ndarray
    weapon: np.ndarray
    vertical_speed: np.ndarray


def _players(
    frames: list[FrameState], ticks: np.ndarray
) -> tuple[list[PlayerInfo], dict[str, np.ndarray]]:
    """Gather every player entry of the frames and build the (P, F) arrays."""
    return player_arrays(_entries(frames, ticks), ticks)


def _entries(frames: list[FrameState], ticks: np.ndarray) -> PlayerRows:
    """Every player entry of ESTA frames as long-form rows; a bad steamID raises."""
    entries: list[PlayerState] = []
    frame_of: list[int] = []
    side_of: list[Side] = []
    for j, frame in enumerate(frames):
        teams: tuple[tuple[Side, TeamState | None], ...] = (("T", frame.t), ("CT", frame.ct))
        for side, team in teams:
            if team is not None and team.players:
                entries.extend(team.players)
                frame_of.extend([j] * len(team.players))
                side_of.extend([side] * len(team.players))
    steam_ids: list[int | None] = []
    keys: list[str] = []
    for e, player in enumerate(entries):
        raw_id = player.steamID
        steam_id = None if raw_id is None else _steam_id(raw_id, ticks, frame_of[e])
        steam_ids.append(steam_id)
        keys.append(str(steam_id) if steam_id is not None else (player.name or ""))

    def numbers(field: str) -> np.ndarray:
        return np.array([getattr(p, field) for p in entries], dtype=np.float64)

    def flags(field: str) -> np.ndarray:
        return np.array([getattr(p, field) is True for p in entries], dtype=bool)

    return PlayerRows(
        frame=np.array(frame_of, dtype=np.int64),
        key=np.array(keys, dtype=object),
        name=np.array([p.name or "" for p in entries], dtype=object),
        steam_id=np.array(steam_ids, dtype=object),
        side=np.array(side_of, dtype=object),
        position=np.array([(p.x, p.y, p.z) for p in entries], dtype=np.float64).reshape(
            len(entries), 3
        ),
        located=np.array(
            [p.x is not None and p.y is not None and p.z is not None for p in entries], bool
        ),
        yaw=numbers("viewX"),
        hp=numbers("hp"),
        armor=numbers("armor"),
        helmet=flags("hasHelmet"),
        has_defuser=flags("hasDefuse"),
        has_bomb=flags("hasBomb"),
        alive=np.array(
            [np.nan if p.isAlive is None else float(p.isAlive) for p in entries], np.float64
        ),
        weapon=np.array([p.activeWeapon or "" for p in entries], dtype=object),
        vertical_speed=numbers("velocityZ"),
    )


def player_arrays(
    rows: PlayerRows, ticks: np.ndarray
) -> tuple[list[PlayerInfo], dict[str, np.ndarray]]:
    """Key, validate and scatter long-form player rows into (P, F) arrays over the frames at
    `ticks`: the players (T first, then CT, each by key) and the arrays of `FrameArrays`."""
    num_frames = len(ticks)
    frame_idx = rows.frame
    empty = np.flatnonzero(rows.key == "")
    if empty.size:
        raise Invalid(
            f"{_where(ticks, int(frame_idx[empty[0]]))}: a player has neither steamID nor name"
        )
    # a player seen on both sides gets a row per side (plausibility.py)
    pairs = pd.MultiIndex.from_arrays([rows.key, rows.side]) if len(rows.key) else None
    codes, uniques = pd.factorize(pairs) if pairs is not None else (np.zeros(0, np.int64), [])
    first = np.zeros(len(uniques), dtype=np.int64)
    if len(codes):
        first[codes[::-1]] = np.arange(len(codes))[::-1]
    infos = [
        PlayerInfo(
            str(rows.key[e]),
            str(rows.name[e] or rows.key[e]),
            rows.steam_id[e],
            rows.side[e],
        )
        for e in first
    ]
    if len(infos) > MAX_PLAYERS:
        raise Invalid(
            f"{len(infos):,} distinct players in the frames (a server has at most {MAX_PLAYERS})"
        )
    # T before CT, each by key: a stable order whatever the order inside the frames.
    order = sorted(range(len(infos)), key=lambda i: (infos[i].side != "T", infos[i].key))
    rank = np.empty(len(infos), dtype=np.int64)
    rank[order] = np.arange(len(infos))
    players = [infos[i] for i in order]
    player_of = rank[codes].astype(np.int64)
    _check_unique(player_of, frame_idx, players, ticks, num_frames)

    placed = _placed(rows.position, rows.located, player_of, frame_idx, players, ticks)
    hp = _counts(rows.hp, "hp", player_of, frame_idx, players, ticks)
    armor = _counts(rows.armor, "armor", player_of, frame_idx, players, ticks)
    _check_weapons(rows.weapon, player_of, frame_idx, players, ticks)
    alive = np.where(np.isnan(rows.alive), hp > 0, rows.alive == 1.0)

    shape = (len(players), num_frames)
    p, f = player_of[placed], frame_idx[placed]

    def scatter(values: np.ndarray, fill: float | str, dtype: npt.DTypeLike) -> np.ndarray:
        """(P, F, ...) array holding each placed entry's value in its cell, `fill` elsewhere."""
        out = np.full(shape + values.shape[1:], fill, dtype=dtype)
        out[p, f] = values[placed]
        return out

    weapons = rows.weapon.astype(str) if len(rows.weapon) else np.zeros(0, dtype="<U1")
    width = max(weapons.dtype.itemsize // 4, 1)
    return players, dict(
        position=scatter(rows.position * HAMMER_TO_M, np.nan, np.float64),
        yaw=scatter(rows.yaw, np.nan, np.float64),
        hp=scatter(hp, MISSING, np.int16),
        armor=scatter(armor, MISSING, np.int16),
        helmet=scatter(rows.helmet, False, bool),
        has_defuser=scatter(rows.has_defuser, False, bool),
        weapon=scatter(weapons, "", f"<U{width}"),
        alive=scatter(alive, False, bool),
        present=scatter(np.ones(len(player_of), dtype=bool), False, bool),
        has_bomb=scatter(rows.has_bomb, False, bool),
        vertical_speed=scatter(
            _vertical_speed(rows.vertical_speed, ticks, frame_idx), np.nan, np.float64
        ),
    )


def _vertical_speed(values: np.ndarray, ticks: np.ndarray, frame_idx: np.ndarray) -> np.ndarray:
    """awpy's `velocityZ` in m/s (NaN where null: not every export has it); 0 on the ground,
    where the Source engine keeps no vertical velocity."""
    bad = np.abs(values) * HAMMER_TO_M > MAX_VELOCITY_M_S  # infinities too, not NaN
    if bad.any():
        e = int(np.flatnonzero(bad)[0])
        raise Invalid(f"{_where(ticks, int(frame_idx[e]))}: velocityZ {values[e]} is not a speed")
    return values * HAMMER_TO_M


def _check_unique(
    player_of: np.ndarray,
    frame_idx: np.ndarray,
    players: list[PlayerInfo],
    ticks: np.ndarray,
    num_frames: int,
) -> None:
    """A player may appear once per frame."""
    cell = player_of * max(num_frames, 1) + frame_idx
    ordered = np.sort(cell)
    repeated = ordered[1:][np.diff(ordered) == 0]
    if repeated.size:
        i, j = divmod(int(repeated[0]), max(num_frames, 1))
        raise Invalid(f"{_where(ticks, j)}: player {players[i].key} appears twice")


def _placed(
    position: np.ndarray,
    located: np.ndarray,
    player_of: np.ndarray,
    frame_idx: np.ndarray,
    players: list[PlayerInfo],
    ticks: np.ndarray,
) -> np.ndarray:
    """Which entries have a position (the others are absent from the frame); NaN or off-map
    raises."""
    null = ~located
    with np.errstate(invalid="ignore"):
        bad = ~null & ~(np.abs(position) <= MAX_COORD_U).all(axis=1)
    if bad.any():
        e = int(np.argmax(bad))
        x, y, z = position[e]
        raise Invalid(
            f"{_where(ticks, int(frame_idx[e]))}: player {players[player_of[e]].key} position "
            f"({x:.1f}, {y:.1f}, {z:.1f}) u is NaN or off the map (beyond ±{MAX_COORD_U:,.0f} u)"
        )
    return ~null


def _counts(
    values: np.ndarray,
    field: str,
    player_of: np.ndarray,
    frame_idx: np.ndarray,
    players: list[PlayerInfo],
    ticks: np.ndarray,
) -> np.ndarray:
    """hp or armor as int16 per entry: MISSING where null or NaN; out of 0..32767 raises."""
    known = np.isfinite(values)
    with np.errstate(invalid="ignore"):
        out_of_range = (values < 0) | (values > np.iinfo(np.int16).max)
    bad = np.isinf(values) | (known & out_of_range)
    if bad.any():
        e = int(np.argmax(bad))
        raise Invalid(
            f"{_where(ticks, int(frame_idx[e]))}: player {players[player_of[e]].key} {field} "
            f"{values[e]:g} is out of range"
        )
    return np.where(known, np.rint(np.where(known, values, 0)), MISSING).astype(np.int16)


def _check_weapons(
    names: np.ndarray,
    player_of: np.ndarray,
    frame_idx: np.ndarray,
    players: list[PlayerInfo],
    ticks: np.ndarray,
) -> None:
    """Every weapon in hand ("" where none) is in the weapon table; another name raises."""
    for name in pd.unique(names):
        if not is_known(name):
            e = int(np.flatnonzero(names == name)[0])
            raise Invalid(
                f"{_where(ticks, int(frame_idx[e]))}: player {players[player_of[e]].key} holds "
                f"unknown weapon {name!r}"
            )
