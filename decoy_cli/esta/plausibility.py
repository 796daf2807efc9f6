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
"""

from __future__ import annotations

import numpy as np

from decoy_cli.csgo import MAX_VELOCITY_M_S
from decoy_cli.esta.frames import FrameArrays
from decoy_cli.esta.schema import Invalid

MAX_HP = 100
MAX_ARMOR = 100
MAX_PER_SIDE = 5
MAX_SPEED_M_S = MAX_VELOCITY_M_S


def check_frames(arrays: FrameArrays) -> None:
    """Raise Invalid naming the first implausible frame and player (see the module doc)."""
    if arrays.ticks.size == 0 or not arrays.players:
        return
    present = arrays.present
    _check_range(arrays, arrays.hp, MAX_HP, "HP")
    _check_range(arrays, arrays.armor, MAX_ARMOR, "armor")
    known = present & (arrays.hp >= 0)
    contradiction = known & (arrays.alive != (arrays.hp > 0))
    if contradiction.any():
        p, f = first_offender(contradiction)
        state = "alive with 0 HP" if arrays.alive[p, f] else f"dead with {arrays.hp[p, f]} HP"
        raise Invalid(f"{_at(arrays, f)}: {arrays.players[p].name} is {state}")
    for side in ("T", "CT"):
        rows = [i for i, player in enumerate(arrays.players) if player.side == side]
        counts = present[rows].sum(axis=0) if rows else np.zeros(arrays.ticks.size, int)
        if counts.max(initial=0) > MAX_PER_SIDE:
            f = int(np.argmax(counts > MAX_PER_SIDE))
            raise Invalid(
                f"{_at(arrays, f)}: {int(counts[f])} {side} players (a side has at most "
                f"{MAX_PER_SIDE})"
            )
    located = present & np.isfinite(arrays.position).all(axis=2)
    if not located.any():  # players are listed, but none ever has a position
        raise Invalid("no player has a position (x, y and z) in any frame")
    _check_speed(arrays, located & arrays.alive)


def _check_range(arrays: FrameArrays, values: np.ndarray, top: int, what: str) -> None:
    bad = arrays.present & (values > top)
    if bad.any():
        p, f = first_offender(bad)
        raise Invalid(
            f"{_at(arrays, f)}: {arrays.players[p].name} has {what} {values[p, f]} (at most {top})"
        )


def _check_speed(arrays: FrameArrays, usable: np.ndarray) -> None:
    """Speed between consecutive frames where the player is alive with a position in both."""
    if arrays.ticks.size < 2:
        return
    step = np.linalg.norm(np.diff(arrays.position, axis=1), axis=2)  # (P, F-1) metres
    dt = np.diff(arrays.seconds)
    both = usable[:, 1:] & usable[:, :-1] & (dt > 0)[None, :]
    speed = np.where(both, step / np.where(dt > 0, dt, 1.0)[None, :], 0.0)
    if speed.max(initial=0.0) > MAX_SPEED_M_S:
        p, k = first_offender(speed > MAX_SPEED_M_S)
        raise Invalid(
            f"{_at(arrays, k + 1)}: {arrays.players[p].name} moved {step[p, k]:.1f} m in "
            f"{dt[k]:.2f} s ({speed[p, k]:.0f} m/s; the engine caps every player at "
            f"{MAX_SPEED_M_S:.1f} m/s)"
        )


def first_offender(mask: np.ndarray) -> tuple[int, int]:
    """(player, frame) of the earliest frame, then the lowest player row, where the (P, F)
    `mask` holds: the cell an error message names."""
    frame = int(np.flatnonzero(mask.any(axis=0))[0])
    player = int(np.flatnonzero(mask[:, frame])[0])
    return player, frame


def _at(arrays: FrameArrays, frame: int) -> str:
    return f"frame {frame} (tick {arrays.ticks[frame]})"
