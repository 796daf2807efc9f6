"""A `decoy evaluate` run's tables as `decoy compare` and `decoy view` read them back:
`rounds.csv`, `players.csv` and `tables/places.csv`, checked column by column.

A run's folder is anyone's to edit. `read_run_table` reads a table from a regular file of at
most `MAX_TABLE_MB`, its text columns as text (a match id "0001" stays "0001"), and checks the
columns the run writes as numbers: every cell a number or empty (`round` a whole number in every
row), and the flags True, False or empty; and the distances (the trajectory metrics, a place's
mean error) in [0, `MAX_METRIC_M`], so that no mean or difference of them overflows (a value
near the float limit made `decoy compare` write `inf`). A cell that is not is one error naming
the file, the column, the data row and the cell, never a ValueError where the numbers are used.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd

from decoy_cli.errors import DecoyError
from decoy_cli.metrics import ALL_METRIC_NAMES
from decoy_cli.reading import read_csv_table
from decoy_cli.text import shortened, visible

MAX_TABLE_MB = 1024
"""Largest table read back: a run of a million player-rounds writes about 400 MB."""

MAX_METRIC_M = 1e9
"""Largest distance a run's metric may be, in metres: a million km, far beyond any replay (the
largest, DTW, sums at most a round's frames times a map's width: under 1e8 m at 128 frames a
second), and far below the float limit, so means and differences of a billion rows are exact
enough and finite."""

_ROUND_COUNTS = (
    "frames",
    "players_t",
    "players_ct",
    "stuck",
    "recoveries",
    "relocations",
    "deaths_original",
    "deaths_replay",
    "deaths_recalled",
    "killers_known",
    "killers_agree",
)
_ROUND_VALUES = (
    "smokes",  # counts, empty where the data has no utility or nobody shot
    "fires",
    "blinds",
    "frame_rate",
    "seconds",
    "played_out_s",
    "wall_seconds",
    "plant_time_error_s",
    "plant_time_resolution_s",
    "plant_position_error_m",
    "defuse_time_error_s",
    "alive_corr",
    "alive_mad",
    "advantage_agreement",
)
_PLAYER_COUNTS = (
    "frames_original",
    "frames_replay",
    "hp_frames",
    "hp_final_original",
    "hp_final_replay",
    "targets",
    "late_over_frame",
    "late_zigzag",
    "late_detour",
    "late_speed",
    "late_gap",
    "late_replay",
    "stuck",
    "recoveries",
    "relocations",
)
_PLAYER_VALUES = (
    "death_time_original_s",
    "death_time_replay_s",
    "hp_rmse",
    "late_share",
    "late_p95_s",
    *ALL_METRIC_NAMES,
)

NUMBER_COLUMNS: dict[str, tuple[str, ...]] = {
    "rounds.csv": ("round", *_ROUND_COUNTS, *_ROUND_VALUES),
    "players.csv": ("round", *_PLAYER_COUNTS, *_PLAYER_VALUES),
    "places.csv": ("mean_error_m",),
}
"""The columns of each table the run writes as numbers (empty where there is none)."""

TEXT_COLUMNS: dict[str, tuple[str, ...]] = {
    "rounds.csv": (
        "match",
        "file",
        "file_sha",
        "winner_original",
        "reason_original",
        "winner_replay",
        "reason_replay",
        "plant_site_data",
        "plant_site_replay",
        "first_death_player_original",
        "first_death_player_replay",
    ),
    "players.csv": ("match", "player", "side", "death", "reason"),
    "places.csv": ("place",),
}
"""Columns read as text whatever they hold (names and ids that may look like numbers)."""

FLAG_COLUMNS: dict[str, tuple[str, ...]] = {
    "rounds.csv": (
        "bomb_recorded",
        "plant_data",
        "plant_replay",
        "defuse_data",
        "defuse_replay",
    ),
    "players.csv": ("died_original", "died_replay"),
}
"""Columns of True and False (empty where there is none)."""

WHOLE_COLUMNS = ("round",)
"""Columns that hold a whole number in every row."""

DISTANCE_COLUMNS = frozenset({*ALL_METRIC_NAMES, "mean_error_m"})
"""Columns of distances in metres, each in [0, `MAX_METRIC_M`] or empty."""

_FLAGS = {"True": True, "False": False, True: True, False: False}


def read_run_table(path: Path, error: type[DecoyError] = DecoyError) -> pd.DataFrame:
    """The run table `path` (rounds.csv, players.csv or places.csv), checked (module doc); a
    missing, unreadable or edited table is one `error` naming it (and the column and row)."""
    text = TEXT_COLUMNS.get(path.name, ())
    frame = read_csv_table(path, error, limit_mb=MAX_TABLE_MB, text=text)
    for column in NUMBER_COLUMNS.get(path.name, ()):
        if column in frame.columns:
            frame[column] = _numbers(path, frame, column, error)
    for column in FLAG_COLUMNS.get(path.name, ()):
        if column in frame.columns:
            frame[column] = _flags(path, frame, column, error)
    return frame


def _numbers(path: Path, frame: pd.DataFrame, column: str, error: type[DecoyError]) -> pd.Series:
    """The column as numbers (int64 for a whole column without gaps, else float64)."""
    cells = frame[column]
    if pd.api.types.is_bool_dtype(cells):
        _refuse(path, column, cells, cells.notna(), "is not a number", error)
    numbers = pd.to_numeric(cells, errors="coerce")
    _refuse(path, column, cells, numbers.isna() & cells.notna(), "is not a number", error)
    if column in DISTANCE_COLUMNS:
        inside = (numbers >= 0) & (numbers <= MAX_METRIC_M)
        why = f"is not a distance in [0, {MAX_METRIC_M:g}] m"
        _refuse(path, column, cells, numbers.notna() & ~inside, why, error)
    if column in WHOLE_COLUMNS:
        values = numbers.to_numpy(np.float64)
        whole = np.isfinite(values) & (np.abs(values) < 2**31) & (values == np.round(values))
        _refuse(path, column, cells, pd.Series(~whole), "is not a whole number", error)
        return pd.Series(values.astype(np.int64), index=cells.index, name=column)
    return numbers


def _flags(path: Path, frame: pd.DataFrame, column: str, error: type[DecoyError]) -> pd.Series:
    """The column as True, False or missing."""
    cells = frame[column]
    if pd.api.types.is_bool_dtype(cells):
        return cells
    known = cells.map(lambda v: v in _FLAGS if isinstance(v, str | bool) else False)
    _refuse(path, column, cells, ~known & cells.notna(), "is not True or False", error)
    return cells.map(lambda v: _FLAGS.get(v) if isinstance(v, str | bool) else None)


def _refuse(
    path: Path,
    column: str,
    cells: pd.Series,
    bad: pd.Series,
    why: str,
    error: type[DecoyError],
) -> None:
    """An `error` naming the first `bad` cell of the column, when there is one."""
    rows = np.flatnonzero(bad.to_numpy(bool))
    if len(rows):
        value = cells.iloc[rows[0]]
        cell = "an empty cell" if pd.isna(value) else repr(visible(shortened(str(value))))
        raise error(
            f"{path}: column {column}, data row {rows[0] + 1}: {cell} {why}"
            f"{f' ({len(rows)} such rows)' if len(rows) > 1 else ''}: an edited or foreign table"
        )
