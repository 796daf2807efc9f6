"""How fast an interval of a plan asks a player to run, and how its time is shared.

An interval's time goes to its path's rises, falls and climbs first (at the game's own speeds,
`graph.edge_fixed_s`); the rest is its running time, in which the run of the path
(`graph.edge_run_m`) is covered at one speed. `asks_more` is the one rule for which intervals
ask more than a speed limit, and why; `build_plan` asks it with the weapon's maximum and the
lateness attribution with the replay's caps.
"""

from __future__ import annotations

import math

import numpy as np

from decoy_cli.csgo import TICK_RATE

MAX_ZIGZAG = 1.3
"""Largest path-over-straight-line factor by which a replay may outrun the player."""

RATIO_TOLERANCE = 1e-9
"""An interval is infeasible when its speed ratio exceeds 1 by more than rounding."""

ZIGZAG_MAX = math.cos(math.pi / 8) + (math.sqrt(2) - 1) * math.sin(math.pi / 8) + 1e-6
"""The longest an eight-way lattice path is against the straight line between its ends: 1.0824,
22.5° off a lattice axis (straight steps along the axis, then diagonal ones). A way round no
longer than this is the lattice's zig-zag; a longer one goes round something."""

MIN_RUN_S = 1.0 / TICK_RATE
"""Shortest running time an interval is given (one simulator tick) when its jumps and falls
alone take all of it: the required speed is then very large, not infinite."""


def asks_more(
    required: np.ndarray,
    straight: np.ndarray,
    running: np.ndarray,
    length: np.ndarray,
    limit: np.ndarray,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Which intervals ask for more than a speed `limit` (m/s, per interval): (over the limit;
    only by the graph's way, the straight line between the two waypoints would be within it;
    of those, only by the lattice's zig-zag, `ZIGZAG_MAX`). `required` is the path's speed over
    the `running` time, `straight` the waypoints' distance, `length` the path's, both less any
    ladder climbed (`interval_straight_run_m`, `interval_run_m`; NaN: unreachable, never a
    zig-zag)."""
    with np.errstate(divide="ignore", invalid="ignore"):
        over = required / limit > 1.0 + RATIO_TOLERANCE
        straight_fits = straight / running / limit <= 1.0 + RATIO_TOLERANCE
    detour = over & straight_fits
    return over, detour, detour & (length <= ZIGZAG_MAX * straight)


def less_climbed(distance: np.ndarray, length: np.ndarray, run: np.ndarray) -> np.ndarray:
    """A straight `distance` less what a path of `length`, of which `run` is run, climbs or
    falls (ladders, ledges; at least 0; NaN lengths: nothing): what the player's own speed must
    cover."""
    return np.maximum(distance - np.nan_to_num(length - run, nan=0.0), 0.0)


def running_seconds(seconds: np.ndarray, air: np.ndarray) -> np.ndarray:
    """The time an interval leaves for running: its `seconds` less the `air` time its path
    spends rising, falling or climbing (not at the player's own speed), at least `MIN_RUN_S`."""
    return np.maximum(seconds - air, MIN_RUN_S)


def edge_durations(
    seconds: np.ndarray,
    length: np.ndarray,
    air: np.ndarray,
    total_length: np.ndarray,
    total_air: np.ndarray,
    on_edge: np.ndarray,
) -> np.ndarray:
    """Each action's share of its interval's `seconds` (all arrays per action, the totals those
    of its interval): an edge gets its time in the air (rising, falling, climbing), and the rest
    of the interval by length, run at one speed (all of it by air time when the air time alone
    exceeds it, or when nothing of the path is run: a ladder alone); a STOP or a RELOCATE gets
    the whole interval."""
    by_air = (total_air > 0) & ((seconds <= total_air) | (total_length <= 0))
    with np.errstate(divide="ignore", invalid="ignore"):
        shared = np.where(
            by_air,
            seconds * air / total_air,
            air + (seconds - total_air) * length / total_length,
        )
    return np.where(on_edge, shared, seconds)
