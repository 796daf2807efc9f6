"""What a round's frames may not hold: data no CS:GO round can produce, caught before anything
is replayed or measured, so a broken file fails by name instead of giving numbers that look
like results.

Each check names the first offending frame and player. The thresholds come from the game's
rules or from measurement on the real ESTA rounds in ../shared/data (the README lists them):

* HP and armor lie in 0..100 (the game's range);
* a player alive in a frame has HP above 0 and a dead one has none (never contradicted in the
  real rounds);
* the history is one a round can have: nothing in CS:GO revives a player or gives back health
  within a round (no one is alive again after being dead, no HP rises from one frame with HP to
  the next), and a player keeps one side (never seen for both);
* at most `MAX_PER_SIDE` players per side in a frame (competitive 5 against 5);
* no alive player moves faster between two frames than the engine's velocity cap
  (sv_maxvelocity, 3500 u/s, about 67 m/s; the fastest real movement measured between two
  frames is about 10 m/s): faster is a teleport or a broken position, not a player;
* players that appear in the frames have a position somewhere (x, y and z);
* across the rounds of a file (`round_order_problems`), the game's clock runs forwards: no round
  starts before the round numbered before it has ended.

The policy (`Implausible`) decides what a problem does: "fail" (the default) makes the round a
failure naming the first offender; "warn" keeps the round and returns one warning per kind of
problem, for data a user has looked at and wants replayed anyway. A round in which no player
ever has a position fails under both: there is nothing to replay or measure.
"""

from __future__ import annotations

from collections.abc import Callable
from itertools import pairwise
from typing import Literal

import numpy as np

from decoy_cli.csgo import MAX_VELOCITY_M_S
from decoy_cli.esta.frames import FrameArrays
from decoy_cli.esta.schema import Invalid

MAX_HP = 100
MAX_ARMOR = 100
MAX_PER_SIDE = 5
MAX_SPEED_M_S = MAX_VELOCITY_M_S

Implausible = Literal["fail", "warn"]
"""What an implausible round does: fail (default) or replay with warnings (module doc)."""


def check_frames(arrays: FrameArrays, policy: Implausible = "fail") -> tuple[str, ...]:
    """The round's implausibility warnings under `policy` (module doc): with "fail", raise
    Invalid naming the first offending frame and player instead."""
    if arrays.ticks.size == 0 or not arrays.players:
        return ()
    located = arrays.present & np.isfinite(arrays.position).all(axis=2)
    if not located.any():  # players are listed, but none ever has a position
        raise Invalid("no player has a position (x, y and z) in any frame")
    problems = []
    for check in _CHECKS:
        problem = check(arrays)
        if problem is not None:
            if policy == "fail":
                raise Invalid(problem)
            problems.append(problem)
    return tuple(problems)


def _hp(arrays: FrameArrays) -> str | None:
    return _out_of_range(arrays, arrays.hp, MAX_HP, "HP")


def _armor(arrays: FrameArrays) -> str | None:
    return _out_of_range(arrays, arrays.armor, MAX_ARMOR, "armor")


def _out_of_range(arrays: FrameArrays, values: np.ndarray, top: int, what: str) -> str | None:
    bad = arrays.present & (values > top)
    if not bad.any():
        return None
    p, f = first_offender(bad)
    return f"{_at(arrays, f)}: {arrays.players[p].name} has {what} {values[p, f]} (at most {top})"


def _alive_against_hp(arrays: FrameArrays) -> str | None:
    known = arrays.present & (arrays.hp >= 0)
    contradiction = known & (arrays.alive != (arrays.hp > 0))
    if not contradiction.any():
        return None
    p, f = first_offender(contradiction)
    state = "alive with 0 HP" if arrays.alive[p, f] else f"dead with {arrays.hp[p, f]} HP"
    return f"{_at(arrays, f)}: {arrays.players[p].name} is {state}"


def _revival(arrays: FrameArrays) -> str | None:
    """Alive in a frame after being dead in an earlier one (where the player is listed)."""
    dead = arrays.present & ~arrays.alive
    revived = arrays.present & arrays.alive & np.logical_or.accumulate(dead, axis=1)
    if not revived.any():
        return None
    p, f = first_offender(revived)
    since = int(np.argmax(dead[p]))
    return (
        f"{_at(arrays, f)}: {arrays.players[p].name} is alive again after being dead in frame "
        f"{since} (nothing revives a player within a round)"
    )


def _hp_rising(arrays: FrameArrays) -> str | None:
    """More HP than at the player's previous frame with a known HP."""
    known = arrays.present & (arrays.hp >= 0)
    frames = np.arange(arrays.ticks.size)
    last = np.maximum.accumulate(np.where(known, frames, -1), axis=1)  # (P, F) latest known
    before = np.concatenate([np.full((known.shape[0], 1), -1), last[:, :-1]], axis=1)
    earlier = np.take_along_axis(arrays.hp, np.maximum(before, 0), axis=1)
    rising = known & (before >= 0) & (arrays.hp > earlier)
    if not rising.any():
        return None
    p, f = first_offender(rising)
    return (
        f"{_at(arrays, f)}: {arrays.players[p].name}'s HP rose to {arrays.hp[p, f]} from "
        f"{earlier[p, f]} in frame {before[p, f]} (nothing gives back health within a round)"
    )


def _both_sides(arrays: FrameArrays) -> str | None:
    """A player (steamID, else name) seen for T and for CT: two rows with one key (frames.py)."""
    rows: dict[str, list[int]] = {}
    for i, player in enumerate(arrays.players):
        rows.setdefault(player.key, []).append(i)
    found = []
    for t_row, *ct_rows in (r for r in rows.values() if len(r) > 1):  # T rows come first
        t_first, ct_first = (int(np.argmax(arrays.present[i])) for i in (t_row, ct_rows[0]))
        found.append((max(t_first, ct_first), t_first, ct_first, t_row))
    if not found:
        return None
    f, t_first, ct_first, row = min(found)
    name = arrays.players[row].name
    if t_first == ct_first:
        doing = "is listed for T and for CT"
    else:
        (now, since), was = (
            (("CT", t_first), "T") if ct_first > t_first else (("T", ct_first), "CT")
        )
        doing = f"plays for {now} after playing for {was} since frame {since}"
    return f"{_at(arrays, f)}: {name} {doing} (a player keeps one side within a round)"


def _players_per_side(arrays: FrameArrays) -> str | None:
    for side in ("T", "CT"):
        rows = [i for i, player in enumerate(arrays.players) if player.side == side]
        counts = arrays.present[rows].sum(axis=0) if rows else np.zeros(arrays.ticks.size, int)
        if counts.max(initial=0) > MAX_PER_SIDE:
            f = int(np.argmax(counts > MAX_PER_SIDE))
            return (
                f"{_at(arrays, f)}: {int(counts[f])} {side} players (a side has at most "
                f"{MAX_PER_SIDE})"
            )
    return None


def _speed(arrays: FrameArrays) -> str | None:
    """Speed between consecutive frames where the player is alive with a position in both."""
    if arrays.ticks.size < 2:
        return None
    usable = arrays.present & arrays.alive & np.isfinite(arrays.position).all(axis=2)
    step = np.linalg.norm(np.diff(arrays.position, axis=1), axis=2)  # (P, F-1) metres
    dt = np.diff(arrays.seconds)
    both = usable[:, 1:] & usable[:, :-1] & (dt > 0)[None, :]
    speed = np.where(both, step / np.where(dt > 0, dt, 1.0)[None, :], 0.0)
    if speed.max(initial=0.0) <= MAX_SPEED_M_S:
        return None
    p, k = first_offender(speed > MAX_SPEED_M_S)
    return (
        f"{_at(arrays, k + 1)}: {arrays.players[p].name} moved {step[p, k]:.1f} m in "
        f"{dt[k]:.2f} s ({speed[p, k]:.0f} m/s; the engine caps every player at "
        f"{MAX_SPEED_M_S:.1f} m/s)"
    )


_CHECKS: tuple[Callable[[FrameArrays], str | None], ...] = (
    _hp,
    _armor,
    _alive_against_hp,
    _revival,
    _hp_rising,
    _both_sides,
    _players_per_side,
    _speed,
)


def round_order_problems(spans: list[tuple[int, int, int]]) -> dict[int, str]:
    """The rounds of a file that start before the round numbered before them has ended, each
    with its problem: `spans` holds (round number, start tick, end tick) of the rounds that
    have ticks. The game's tick only runs forwards, so such a file's clock contradicts
    itself; the later round is the one named."""
    problems = {}
    ordered = sorted(spans)
    for (before, _, end), (num, start, _) in pairwise(ordered):
        if start < end:
            problems[num] = (
                f"starts at tick {start}, before round {before} has ended (tick {end}): the "
                "file's clock runs backwards"
            )
    return problems


def first_offender(mask: np.ndarray) -> tuple[int, int]:
    """(player, frame) of the earliest frame, then the lowest player row, where the (P, F)
    `mask` holds: the cell an error message names."""
    frame = int(np.flatnonzero(mask.any(axis=0))[0])
    player = int(np.flatnonzero(mask[:, frame])[0])
    return player, frame


def _at(arrays: FrameArrays, frame: int) -> str:
    return f"frame {frame} (tick {arrays.ticks[frame]})"
