"""What a round's frames may not hold: data no CS:GO round can produce, caught before anything
is replayed or measured, so a broken file fails by name instead of giving numbers that look
like results.

Each check names the first offending frame and player. The thresholds come from the game's
rules or from measurement on the real ESTA rounds in ../shared/data (the README lists them):

* HP and armor lie in 0..100 (the game's range);
* a player alive in a frame has HP above 0 and a dead one has none (never contradicted in the
  real rounds);
* at most `MAX_PER_SIDE` players per side in a frame (competitive 5 against 5);
* no alive player moves faster between two frames than the engine's velocity cap
  (sv_maxvelocity, 3500 u/s, about 67 m/s; the fastest real movement measured between two
  frames is about 10 m/s): faster is a teleport or a broken position, not a player;
* players that appear in the frames have a position somewhere (x, y and z).

The policy (`Implausible`) decides what a problem does: "fail" (the default) makes the round a
failure naming the first offender; "warn" keeps the round and returns one warning per kind of
problem, for data a user has looked at and wants replayed anyway. A round in which no player
ever has a position fails under both: there is nothing to replay or measure.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Literal, cast, get_args

import numpy as np

from decoy_cli.csgo import MAX_VELOCITY_M_S
from decoy_cli.errors import EstaError
from decoy_cli.esta.frames import FrameArrays
from decoy_cli.esta.schema import Invalid

MAX_HP = 100
MAX_ARMOR = 100
MAX_PER_SIDE = 5
MAX_SPEED_M_S = MAX_VELOCITY_M_S

Implausible = Literal["fail", "warn"]
"""What an implausible round does: fail (default) or replay with warnings (module doc)."""
IMPLAUSIBLE_CHOICES: tuple[str, ...] = get_args(Implausible)


def check_policy(value: str) -> Implausible:
    """`value` as a policy if it is one of `IMPLAUSIBLE_CHOICES`, else an EstaError naming them."""
    if value not in IMPLAUSIBLE_CHOICES:
        raise EstaError(f"--implausible {value!r}: use {' or '.join(IMPLAUSIBLE_CHOICES)}")
    return cast(Implausible, value)


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
    _players_per_side,
    _speed,
)


def first_offender(mask: np.ndarray) -> tuple[int, int]:
    """(player, frame) of the earliest frame, then the lowest player row, where the (P, F)
    `mask` holds: the cell an error message names."""
    frame = int(np.flatnonzero(mask.any(axis=0))[0])
    player = int(np.flatnonzero(mask[:, frame])[0])
    return player, frame


def _at(arrays: FrameArrays, frame: int) -> str:
    return f"frame {frame} (tick {arrays.ticks[frame]})"
