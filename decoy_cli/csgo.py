"""CS:GO facts the whole project shares: units, player dimensions, movement limits.

Everything inside the project is in metres (x east, y north, z up, as in the Source engine);
Hammer units are converted once where data enters (the ESTA reader, the nav assets, user meshes).
"""

from __future__ import annotations

import math

HAMMER_TO_M = 0.01905
"""One Hammer unit in metres."""

PLAYER_RADIUS_M = 16 * HAMMER_TO_M
"""Half the width of the 32 x 32 u standing player hull."""

PLAYER_HEIGHT_M = 72 * HAMMER_TO_M
"""Standing hull height."""

EYE_HEIGHT_M = 64 * HAMMER_TO_M
"""Standing eye height above the feet."""

STEP_HEIGHT_M = 18 * HAMMER_TO_M
"""Highest ledge a player walks up without jumping (sv_stepsize 18)."""

JUMP_HEIGHT_M = 64 * HAMMER_TO_M
"""Highest ledge a player reaches with a crouch-jump (a plain jump clears about 55.8 u)."""

MAX_DROP_M = 210 * HAMMER_TO_M
"""Deepest drop the waypoint builder links: the safe fall (580 u/s at 800 u/s² gravity, ~210 u)."""

TICK_RATE = 60
"""Physics ticks per second of the simulator."""

GRAVITY_M_S2 = 800 * HAMMER_TO_M
"""Gravity (sv_gravity 800 u/s²)."""

JUMP_SPEED_M_S = 301.99 * HAMMER_TO_M
"""Upward speed a jump starts with (sqrt(2 * 800 * 57) u/s): a plain jump rises about 57 u."""


def seconds_to_ticks(seconds: float, tick_rate: int = TICK_RATE) -> int:
    """A duration as a whole number of ticks, rounded up so that no rule runs shorter than in the
    game. The product is first rounded to 1e-6, so float noise adds no tick: 8.3 * 60 is
    498.00000000000006 and gives 498, not 499."""
    return math.ceil(round(seconds * tick_rate, 6))


def tick_at(seconds: float, tick_rate: int = TICK_RATE) -> int:
    """The tick nearest a moment in time (seconds on the round's clock): where data frames,
    deadlines and recorded events fall."""
    return round(float(seconds) * tick_rate)
