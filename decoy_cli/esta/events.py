"""Event lists of one round (damages, kills, bomb events, flashes) as typed pandas DataFrames.

Columns are the awpy 1.x ones of decoy_cli/esta/schema.py, in that order, whatever keys a file
has (a missing key gives nulls, an unknown key is dropped). Dtypes: nullable `Int64` for counts,
ticks and steamIDs, float64 with NaN for nulls, nullable `boolean`, and strings as pandas
infers them (object, or `str` on pandas 3; null is missing).
Added at the end: `<position column>_m` (attackerX_m, victimZ_m, playerY_m, ...) and `distance_m`
in metres, and `frame_index`, the index of the frame whose tick is nearest the event's tick (the
earlier frame on a tie; -1 without frames or without a tick). The raw Hammer columns stay as
they are. Damage and kill weapons must be in the weapon table, or "World" (fall and world damage).
"""

from __future__ import annotations

from collections.abc import Sequence
from functools import cache
from typing import cast

import msgspec
import numpy as np
import pandas as pd

from decoy_cli.csgo import HAMMER_TO_M
from decoy_cli.esta.frames import MAX_COORD_U, RoundClock
from decoy_cli.esta.schema import Invalid, Kind
from decoy_cli.weapons import is_known

EVENT_ONLY_WEAPONS = frozenset({"World"})
"""Damage sources awpy names in events that nobody holds in a frame."""

_POSITION_OWNERS = ("attacker", "victim", "player")
_MAX_INT64 = 2**63 - 1
_MAX_EXACT = 2.0**53


def build_table(
    table: str,
    rows: Sequence[msgspec.Struct] | None,
    columns: dict[str, Kind],
    frame_ticks: np.ndarray,
    clock: RoundClock | None = None,
) -> pd.DataFrame:
    """One event list as a DataFrame with metre columns and `frame_index`; bad rows raise.
    With the round's `clock`, `seconds` is the clock's reading at each event's tick (where the
    event has one), as for the frames."""
    if not rows:
        return _empty_table(table, tuple(columns.items())).copy()
    return _build(table, rows, columns, frame_ticks, clock)


@cache
def _empty_table(table: str, columns: tuple[tuple[str, Kind], ...]) -> pd.DataFrame:
    """The table without rows, built once: most rounds of the T-side files have no events."""
    return _build(table, [], dict(columns), np.empty(0, dtype=np.int64), None)


def _build(
    table: str,
    rows: Sequence[msgspec.Struct],
    columns: dict[str, Kind],
    frame_ticks: np.ndarray,
    clock: RoundClock | None,
) -> pd.DataFrame:
    """The table of `build_table`, for any number of rows."""
    data: dict[str, object] = {
        column: _column(table, column, kind, [getattr(row, column) for row in rows])
        for column, kind in columns.items()
    }
    for owner in _POSITION_OWNERS:
        for axis in "XYZ":
            column = f"{owner}{axis}"
            if column in columns:
                data[f"{column}_m"] = _metres(table, column, data[column])
    if "distance" in columns:
        data["distance_m"] = np.asarray(data["distance"]) * HAMMER_TO_M
    if "weapon" in columns and table != "bomb_events":
        _check_weapons(table, np.asarray(data["weapon"]))
    ticks = cast(pd.arrays.IntegerArray, data["tick"])  # every table's tick is an "int" column
    tick_values = ticks.to_numpy(dtype=np.float64, na_value=np.nan)
    data["frame_index"] = nearest_frame(tick_values, frame_ticks)
    if clock is not None and "seconds" in data:
        written = np.asarray(data["seconds"], dtype=np.float64)
        data["seconds"] = np.where(np.isfinite(tick_values), clock.seconds(tick_values), written)
    return pd.DataFrame(data, index=pd.RangeIndex(len(rows)))


def nearest_frame(ticks: np.ndarray, frame_ticks: np.ndarray) -> np.ndarray:
    """Index of the frame whose tick is nearest each tick (earlier on a tie); -1 for NaN ticks."""
    out = np.full(ticks.shape, -1, dtype=np.int64)
    known = np.isfinite(ticks)
    if frame_ticks.size == 0 or not known.any():
        return out
    t = ticks[known]
    right = np.clip(np.searchsorted(frame_ticks, t, side="left"), 0, frame_ticks.size - 1)
    left = np.clip(right - 1, 0, frame_ticks.size - 1)
    take_left = np.abs(t - frame_ticks[left]) <= np.abs(frame_ticks[right] - t)
    out[known] = np.where(take_left, left, right)
    return out


def _column(table: str, column: str, kind: Kind, values: list) -> object:
    """Typed column values; a count that is not an integer raises."""
    if kind == "float":
        return np.array(values, dtype=np.float64)
    if kind == "str":
        return np.array(values, dtype=object)
    if kind == "bool":
        return pd.arrays.BooleanArray(
            np.array([v is True for v in values], dtype=bool),
            np.array([v is None for v in values], dtype=bool),
        )
    if kind == "int":
        numbers = np.array(values, dtype=np.float64)
        known = ~np.isnan(numbers)
        with np.errstate(invalid="ignore"):
            bad = known & ~((np.abs(numbers) < _MAX_EXACT) & (numbers == np.round(numbers)))
        if bad.any():
            i = int(np.argmax(bad))
            raise Invalid(f"{table}[{i}]: {column} {values[i]!r} is not an integer")
        return pd.arrays.IntegerArray(np.where(known, numbers, 0).astype(np.int64), ~known)
    return _steam_ids(table, column, values)


def _steam_ids(table: str, column: str, values: list) -> pd.arrays.IntegerArray:
    """steamIDs as nullable Int64 (exact: floats only where they hold an integer)."""
    ints = np.zeros(len(values), dtype=np.int64)
    mask = np.zeros(len(values), dtype=bool)
    for i, value in enumerate(values):
        if value is None:
            mask[i] = True
            continue
        exact = isinstance(value, int) or (
            np.isfinite(value) and value == round(value) and abs(value) < _MAX_EXACT
        )
        if not exact or abs(int(value)) > _MAX_INT64:
            raise Invalid(f"{table}[{i}]: {column} {value!r} is not a steamID")
        ints[i] = int(value)
    return pd.arrays.IntegerArray(ints, mask)


def _metres(table: str, column: str, hammer: object) -> np.ndarray:
    """A Hammer-unit position column in metres; an off-map value raises (NaN stays NaN)."""
    values = np.asarray(hammer, dtype=np.float64)
    with np.errstate(invalid="ignore"):
        off = np.abs(values) > MAX_COORD_U
    if off.any():
        i = int(np.argmax(off))
        raise Invalid(
            f"{table}[{i}]: {column} {values[i]:.1f} u is off the map "
            f"(beyond ±{MAX_COORD_U:,.0f} u)"
        )
    return values * HAMMER_TO_M


def _check_weapons(table: str, weapons: np.ndarray) -> None:
    """Every weapon named in damages or kills is in the table (or an event-only source)."""
    names = list(weapons)
    for name in set(names) - {None}:
        if not (is_known(name) or name in EVENT_ONLY_WEAPONS):
            raise Invalid(f"{table}[{names.index(name)}]: unknown weapon {name!r}")
