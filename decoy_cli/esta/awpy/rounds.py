"""awpy's tables, opened as one shape (decoy_cli/esta/awpy/tables.py), as a `Match` of `Round`s.

The same `Round` an ESTA file gives: frames run from freeze-time end on the game's clock, players
keyed by steamID where the data has one, else by name, T before CT; positions in metres; events
as ESTA's tables with its names (decoy_cli/esta/awpy/names.py).

* **Rounds and time.** Start, freeze end, end and official end from the rounds table; a tick
  table row or an event belongs to the round whose start is the latest at or before its tick, up
  to that round's official end (awpy 2's own rule; a tick equal to one round's end and the next
  one's start is the next round's). The tick rate is the demo's (decoy_cli/esta/awpy/reader.py).
* **Frames at a rate.** Full-rate ticks are sampled at `rate` frames a second on the grid from
  freeze-time end (the first tick at or after each grid point, so a missing tick moves a frame
  and never drops it); ticks already sampled at or below that rate are kept as they are.
* **What the data lacks.** A tick column that is absent, all null or one constant over the whole
  table (awpy 3's stand-ins: armour 0, yaw 0.0) is not recorded: the round holds it as absent
  (-1, NaN, "", False) and names it in `Round.not_recorded`, so the replay fills it by the rules
  of decoy_cli/replay/missing.py and says so.
* **Coordinates** are awpy's float32, widened exactly to float64.
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np
import pandas as pd

from decoy_cli.errors import EstaError
from decoy_cli.esta.awpy.events import is_null, round_events, row_keys, texts, utility_table
from decoy_cli.esta.awpy.names import (
    Spelling,
    bomb_site,
    end_reason,
    side_name,
    weapon_name,
)
from decoy_cli.esta.events import build_table
from decoy_cli.esta.frames import (
    MAX_FRAMES,
    FrameArrays,
    PlayerRows,
    RoundClock,
    check_clock,
    player_arrays,
)
from decoy_cli.esta.plausibility import Implausible, check_frames
from decoy_cli.esta.reader import Match, Round, round_from_frames
from decoy_cli.esta.schema import (
    BOMB_EVENT_COLUMNS,
    DAMAGE_COLUMNS,
    FLASH_COLUMNS,
    KILL_COLUMNS,
    Invalid,
)
from decoy_cli.files import JsonObject

DEFAULT_RATE = 8.0
"""Frames a second taken from full-rate ticks unless `--rate` says otherwise (docs/cs2.md says
what it trades)."""

NOT_RECORDED = {
    "yaw": "view angles",
    "armor": "armour, helmet and kit",
    "weapon": "weapon in hand",
    "velocity_z": "vertical speed",
    "steamid": "steamids",
}
"""Tick columns a source may lack, by the name a round's `not_recorded` gives them."""
MAX_YAW = 720.0
"""Largest |yaw| a view angle can be written as, degrees (awpy writes -180..180 or 0..360)."""
CARRIER = "bomb carrier"
UTILITY = "utility (smokes, fires, blinds)"
"""Named not recorded where the match's tables hold no smoke, fire or blind at all: a real
match always has some."""
EQUIPMENT = ("armor", "has_helmet", "has_defuser")


@dataclass(frozen=True)
class RoundWindow:
    """One row of the rounds table: ticks and outcome (`winner`, `reason` as awpy has them)."""

    num: int
    start: int
    freeze_end: int
    end: int
    official_end: int
    winner: object
    reason: object
    plant_tick: int | None
    plant_site: str


@dataclass(frozen=True, eq=False)
class AwpyTables:
    """A match's awpy tables under the reader's names (decoy_cli/esta/awpy/layouts.py): the
    rounds as windows, each round's frame ticks, the kept tick rows and the event tables."""

    path: Path
    match_id: str
    layout: str
    header: JsonObject
    map_name: str
    tick_rate: int
    tick_weapons: Spelling
    windows: list[RoundWindow]
    frames: list[np.ndarray]
    ticks: pd.DataFrame
    kills: pd.DataFrame
    damages: pd.DataFrame
    bomb: pd.DataFrame
    smokes: pd.DataFrame | None = None
    fires: pd.DataFrame | None = None
    blinds: pd.DataFrame | None = None
    """None: the source does not hold the table (utility not recorded)."""


def read_tables_match(tables: AwpyTables, *, implausible: Implausible) -> Match:
    """Every round of the tables, built, or its error kept by round number (as `read_match`)."""
    not_recorded = _not_recorded(tables.ticks)
    if all(t is None or not len(t) for t in (tables.smokes, tables.fires, tables.blinds)):
        not_recorded += (UTILITY,)
    ticks = tables.ticks.drop(columns=[c for c in tables.ticks if c in _dropped(not_recorded)])
    owner = assign_rounds(ticks["tick"].to_numpy(np.int64), tables.windows)
    rounds: list[Round] = []
    errors: dict[int, EstaError] = {}
    for index, window in enumerate(tables.windows):
        try:
            rows = ticks[owner == index]
            built = _build_round(tables, window, tables.frames[index], rows, implausible)
            lacking = (*not_recorded, *_carrier(rows))
            rounds.append(replace(built, not_recorded=lacking))
        except Invalid as problem:
            errors[window.num] = EstaError(f"{tables.path}: round {window.num}: {problem}")
    return Match(
        match_id=tables.match_id,
        path=tables.path,
        map_name=tables.map_name,
        tick_rate=tables.tick_rate,
        meta={"source": tables.layout, "header": tables.header},
        rounds=rounds,
        round_errors=dict(sorted(errors.items())),
    )


def _not_recorded(ticks: pd.DataFrame) -> tuple[str, ...]:
    """The optional tick columns that hold no information: absent, all null, or one value in
    every row (awpy 3's stand-ins), by the names of `NOT_RECORDED`."""
    lacking = []
    for column, name in NOT_RECORDED.items():
        if column not in ticks or ticks[column].nunique(dropna=True) <= 1:
            lacking.append(name)
    return tuple(lacking)


def _dropped(not_recorded: tuple[str, ...]) -> set[str]:
    """The tick columns a round holds as absent because the table does not record them."""
    columns = {column for column, name in NOT_RECORDED.items() if name in not_recorded}
    if "armor" in columns:
        columns |= set(EQUIPMENT)
    return columns


def _carrier(rows: pd.DataFrame) -> tuple[str, ...]:
    """The bomb carrier, named not recorded where nobody holds the bomb in a round's rows."""
    if "has_bomb" in rows and rows["has_bomb"].fillna(False).astype(bool).any():
        return ()
    return (CARRIER,)


def round_windows(path: Path, table: pd.DataFrame) -> list[RoundWindow]:
    """The rounds table as windows, in tick order; repeated or overlapping rounds raise."""
    windows = []
    for row in table.to_dict("records"):
        official = row.get("official_end")
        plant = row.get("bomb_plant")
        windows.append(
            RoundWindow(
                num=int(row["round_num"]),
                start=int(row["start"]),
                freeze_end=int(row["freeze_end"]),
                end=int(row["end"]),
                official_end=int(row["end"]) if is_null(official) else int(official),
                winner=row["winner"],
                reason=row["reason"],
                plant_tick=None if is_null(plant) else int(plant),
                plant_site=bomb_site(row.get("bomb_site")),
            )
        )
    windows.sort(key=lambda w: w.start)
    numbers = [w.num for w in windows]
    if len(set(numbers)) != len(numbers):
        repeated = sorted({n for n in numbers if numbers.count(n) > 1})
        raise EstaError(f"{path}: the rounds table holds round {repeated[0]} twice")
    for w in windows:
        if not w.start <= w.freeze_end < w.end <= w.official_end:
            raise EstaError(
                f"{path}: round {w.num}: start {w.start}, freeze end {w.freeze_end}, end {w.end} "
                f"and official end {w.official_end} are not in order (a round has play)"
            )
    for before, after in itertools.pairwise(windows):
        if after.start < before.end:
            raise EstaError(
                f"{path}: round {after.num} starts at tick {after.start}, before round "
                f"{before.num} ends (tick {before.end})"
            )
    return windows


def assign_rounds(ticks: np.ndarray, windows: list[RoundWindow]) -> np.ndarray:
    """The index into `windows` of the round each tick belongs to (module docstring), -1 for a
    tick in no round."""
    values = np.asarray(ticks, dtype=np.int64)
    if not windows:
        return np.full(values.shape, -1, dtype=np.int64)
    starts = np.array([w.start for w in windows], dtype=np.int64)
    ends = np.array([w.official_end for w in windows], dtype=np.int64)
    index = np.searchsorted(starts, values, side="right") - 1
    inside = (index >= 0) & (values <= ends[np.clip(index, 0, None)])
    return np.where(inside, index, -1)


def frame_ticks(ticks: np.ndarray, freeze_end: int, step: int) -> np.ndarray:
    """The ticks kept as frames from a round's sorted unique `ticks` from freeze-time end on:
    all of them when they are `step` ticks apart or more (sampled already), else the first tick
    at or after each point of the grid `freeze_end + k * step`."""
    ticks = ticks[ticks >= freeze_end]
    if ticks.size < 2 or step <= 1 or np.median(np.diff(ticks)) >= step:
        return ticks
    grid = np.arange(freeze_end, int(ticks[-1]) + 1, step, dtype=np.int64)
    at = np.searchsorted(ticks, grid, side="left")
    return np.unique(ticks[at[at < ticks.size]])


def _build_round(
    tables: AwpyTables,
    window: RoundWindow,
    kept: np.ndarray,
    rows: pd.DataFrame,
    implausible: Implausible,
) -> Round:
    """One round of the tables (module docstring); a problem raises Invalid."""
    if kept.size == 0:
        raise Invalid("no tick rows from its freeze end to its end")
    if kept.size > MAX_FRAMES:
        raise Invalid(f"{kept.size:,} frames (a round holds at most {MAX_FRAMES:,})")
    warnings: list[str] = []
    winner = side_name(window.winner)
    reason = end_reason(window.reason)
    if winner is None:
        warnings.append(f"winner {window.winner!r} is not a side: no winner")
    if reason is None:
        warnings.append(f"unknown round end reason {window.reason!r}: none kept")
    clock = RoundClock(float(window.freeze_end), tables.tick_rate)
    rows = rows[rows["tick"].to_numpy(np.int64) >= window.freeze_end]
    raw = rows["tick"].to_numpy(np.int64)
    if raw.size and (np.diff(raw) < 0).any():
        rows = rows.sort_values("tick", kind="stable")
        raw = rows["tick"].to_numpy(np.int64)
        warnings.append("the tick table is not in tick order (read sorted)")
    frame = np.searchsorted(kept, raw)
    infos, arrays = player_arrays(_player_rows(rows, frame, tables, warnings), kept)
    seconds = clock.seconds(kept)
    check_clock(seconds, kept)
    planted = (
        (kept >= window.plant_tick) if window.plant_tick is not None else np.zeros(kept.size, bool)
    )
    frames = FrameArrays(
        ticks=kept,
        seconds=seconds,
        clock=clock,
        players=infos,
        **arrays,
        bomb_position=np.full((kept.size, 3), np.nan),
        bomb_planted=planted,
        bombsite=np.array([window.plant_site if p else "" for p in planted], dtype=str),
    )
    warnings.extend(check_frames(frames, implausible))
    events = round_events(
        _in_window(tables.kills, window),
        _in_window(tables.damages, window),
        _in_window(tables.bomb, window),
        rows,
        window.plant_site,
        warnings,
        blinds=None if tables.blinds is None else _in_window(tables.blinds, window),
    )
    smokes = utility_table(_utility_in(tables.smokes, window), "smoke", clock, warnings)
    fires = utility_table(_utility_in(tables.fires, window), "fire", clock, warnings)
    return round_from_frames(
        frames,
        match_id=tables.match_id,
        path=tables.path,
        round_num=window.num,
        map_name=tables.map_name,
        tick_rate=tables.tick_rate,
        damages=build_table("damages", events["damages"], DAMAGE_COLUMNS, kept, clock),
        kills=build_table("kills", events["kills"], KILL_COLUMNS, kept, clock),
        bomb_events=build_table("bomb_events", events["bomb"], BOMB_EVENT_COLUMNS, kept, clock),
        flashes=build_table("flashes", events["flashes"], FLASH_COLUMNS, kept, clock),
        winning_side=winner,  # side_name gives "T", "CT" or None
        end_reason=reason,
        bomb_plant_tick=window.plant_tick,
        start_tick=window.start,
        end_tick=window.end,
        clock=clock,
        warnings=tuple(warnings),
        source=tables.layout,
        smokes=smokes,
        fires=fires,
    )


def _player_rows(
    rows: pd.DataFrame, frame: np.ndarray, tables: AwpyTables, warnings: list[str]
) -> PlayerRows:
    """The round's kept tick rows in the long form `player_arrays` takes."""
    count = len(rows)

    def numbers(column: str) -> np.ndarray:
        if column not in rows:
            return np.full(count, np.nan)
        return rows[column].to_numpy(dtype=np.float64, na_value=np.nan)

    def flags(column: str) -> np.ndarray:
        if column not in rows:
            return np.zeros(count, dtype=bool)
        return rows[column].to_numpy(dtype=object, na_value=False).astype(bool)

    names = texts(rows["name"], "")
    keys, steam = row_keys(rows)
    sides = texts(rows["side"], None)
    side = np.array([side_name(s) or "" for s in sides], dtype=object)
    if (side == "").any():
        bad = sides[int(np.flatnonzero(side == "")[0])]
        raise Invalid(f"a tick row has side {bad!r} (not a team's)")
    position = np.stack([numbers("x"), numbers("y"), numbers("z")], axis=1).reshape(count, 3)
    yaw = numbers("yaw")
    with np.errstate(invalid="ignore"):
        wrong = np.isinf(yaw) | (np.abs(yaw) > MAX_YAW)
    if wrong.any():
        raise Invalid(f"a tick row's yaw {yaw[int(np.argmax(wrong))]:g} is not a view angle")
    alive = numbers("is_alive")
    return PlayerRows(
        frame=frame.astype(np.int64),
        key=keys,
        name=names,
        steam_id=steam,
        side=side,
        position=position,
        located=~np.isnan(position).any(axis=1),
        yaw=yaw % 360.0,
        hp=numbers("health"),
        armor=numbers("armor"),
        helmet=flags("has_helmet"),
        has_defuser=flags("has_defuser"),
        has_bomb=flags("has_bomb"),
        alive=alive,
        weapon=_weapons(rows, tables.tick_weapons, warnings),
        vertical_speed=numbers("velocity_z"),
    )


def _weapons(rows: pd.DataFrame, spelling: Spelling, warnings: list[str]) -> np.ndarray:
    """ESTA's name of each row's weapon in hand; an unknown one is "" and a named warning."""
    if "weapon" not in rows:
        return np.full(len(rows), "", dtype=object)
    raw = texts(rows["weapon"], "")
    codes, names = pd.factorize(raw)
    mapped = []
    for name in names:
        esta = weapon_name(name, spelling)
        if esta is None:
            warnings.append(f"unknown weapon in hand {str(name)!r}: read as none")
        mapped.append(esta or "")
    return np.array(mapped, dtype=object)[codes]


def _in_window(table: pd.DataFrame, window: RoundWindow) -> pd.DataFrame:
    """The rows of an event table in the round (module docstring), in tick order."""
    ticks = table["tick"].to_numpy(dtype=np.int64)
    inside = (ticks >= window.start) & (ticks <= window.official_end)
    return table[inside].sort_values("tick", kind="stable")


def _utility_in(table: pd.DataFrame | None, window: RoundWindow) -> pd.DataFrame | None:
    """The smokes or fires that burst in the round (by `start_tick`), in tick order."""
    if table is None:
        return None
    ticks = table["start_tick"].to_numpy(dtype=np.int64)
    inside = (ticks >= window.start) & (ticks <= window.official_end)
    return table[inside].sort_values("start_tick", kind="stable")
