"""Read an awpy 2 zip, a folder of awpy 3 tables or a demo (through awpy 3) into a `Match`.

The tick table is read twice, and only the second time whole: first its `tick` column alone,
which decides the frames of every round (decoy_cli/esta/awpy/rounds.py), then the rows of those
frames, in batches: a match's memory is the frames it keeps, not the millions of ticks of a
full-rate table. The tick rate is the header's (awpy 3's `playback_ticks / playback_time`, or a
`tick_rate` key); where the header does not give it (awpy 2 writes none), the spans the game's
rules fix tell it: plant to detonation (the 40 s bomb timer) and freeze end to a round lost on
time (the 115 s round time), the median of their ticks per second taken to the nearer of 64 and
128; with neither, CS2's 64. The match says which (`Match.meta["tick_rate_rule"]`).
"""

from __future__ import annotations

import math
import re
from pathlib import Path

import numpy as np
import pandas as pd
import pyarrow as pa
import pyarrow.compute as pc

from decoy_cli.errors import EstaError
from decoy_cli.esta.awpy.layouts import LAYOUTS, Layout, TableLayout
from decoy_cli.esta.awpy.names import bomb_action, bomb_site, end_reason, weapon_name
from decoy_cli.esta.awpy.rounds import (
    AwpyTables,
    RoundWindow,
    assign_rounds,
    frame_ticks,
    read_tables_match,
    round_windows,
)
from decoy_cli.esta.awpy.tables import (
    TableSource,
    open_source,
    read_table,
    stream_table,
    table_rows,
)
from decoy_cli.esta.plausibility import Implausible
from decoy_cli.esta.reader import Match
from decoy_cli.esta.records import BOMB_TIMER_S, ROUND_TIME_S
from decoy_cli.esta.source import MAX_ROUNDS

CS2_TICK_RATE = 64
"""Ticks a second of a CS2 server (sub-tick, 64 ticks/s): the rate where the header gives none."""

MAP_NAME = re.compile(r"[A-Za-z0-9_.-]{1,64}")
"""What a map's name can be (de_dust2, cs_office, workshop names): a short word, no path."""

KNOWN_TICK_RATES = (64, 128)
"""The tick rates of Counter-Strike demos: CS2's 64, CS:GO's 64 and 128."""

MAX_TICK_ROWS = 50_000_000
"""Most rows a tick table may hold: a full-rate 64-tick match of 30 rounds holds about 2 million
(10 players × 64 ticks × ~3,000 s); 25 times that bounds the memory of a hostile table."""


def read_awpy_match(path: Path, *, rate: float, implausible: Implausible = "fail") -> Match:
    """The match in awpy's tables at `path`; `rate` frames a second from full-rate ticks."""
    if not (math.isfinite(rate) and rate > 0):
        raise EstaError(f"the frame rate must be a positive number of frames a second, not {rate}")
    source = open_source(path, rate)
    layout = LAYOUTS[source.layout]
    map_name = source.header.get("map_name")
    if not isinstance(map_name, str) or not MAP_NAME.fullmatch(map_name):
        raise EstaError(f"{path}: header.json names no map (map_name {map_name!r:.60})")
    bomb = _frame(source, layout.bomb)
    rounds = _rounds(source, layout, bomb)
    windows = round_windows(path, rounds)
    tick_rate, rule = _tick_rate(source, windows, bomb)
    rows_held = table_rows(source, layout.ticks.name)  # the footer's count, before any is read
    if rows_held > MAX_TICK_ROWS:
        raise EstaError(f"{path}: {rows_held:,} tick rows, more than {MAX_TICK_ROWS:,}")
    ticks_only = read_table(source, layout.ticks.name, {"tick": "int"}, ("tick",))
    tick_values = _ticks(path, layout.ticks.name, ticks_only["tick"].to_pandas())
    owner = assign_rounds(tick_values, windows)
    if owner.size and (owner < 0).all():
        raise EstaError(
            f"{path}: none of the {owner.size:,} rows of {layout.ticks.name} falls in a round of "
            "its rounds table (tables of two demos?)"
        )
    step = max(1, round(tick_rate / rate))
    kept = [
        frame_ticks(np.unique(tick_values[owner == i]), w.freeze_end, step)
        for i, w in enumerate(windows)
    ]
    wanted = pa.array(np.unique(np.concatenate(kept)) if kept else np.zeros(0, np.int64))
    del ticks_only, tick_values, owner
    rows = stream_table(
        source,
        layout.ticks.name,
        layout.ticks.kinds,
        layout.ticks.required,
        lambda batch: pc.is_in(pc.cast(batch.column("tick"), pa.int64()), value_set=wanted),
    )
    ticks = _to_pandas(rows.rename_columns([layout.ticks.renames[c] for c in rows.column_names]))
    if "inventory" in ticks and "has_bomb" not in ticks:
        ticks["has_bomb"] = ticks.pop("inventory").map(_holds_bomb)
    _check_parts(path, ticks, layout.ticks.name)
    kills = _frame(source, layout.kills)
    if len(kills) and (assign_rounds(kills["tick"].to_numpy(np.int64), windows) < 0).all():
        raise EstaError(
            f"{path}: none of the {len(kills)} kills falls in a round of its rounds table "
            "(tables of two demos?)"
        )
    tables = AwpyTables(
        path=path,
        match_id=path.name.removesuffix(path.suffix) if path.is_file() else path.name,
        layout=source.layout,
        header=source.header,
        map_name=map_name,
        tick_rate=tick_rate,
        tick_weapons=layout.tick_weapons,
        windows=windows,
        frames=kept,
        ticks=ticks,
        kills=kills,
        damages=_damages(source, layout),
        bomb=bomb,
        smokes=_optional_frame(source, layout.smokes),
        fires=_optional_frame(source, layout.fires),
        blinds=_optional_frame(source, layout.blinds),
    )
    match = read_tables_match(tables, implausible=implausible)
    match.meta["tick_rate_rule"] = rule
    return match


def _tick_rate(
    source: TableSource, windows: list[RoundWindow], bomb: pd.DataFrame
) -> tuple[int, str]:
    """The demo's tick rate and where it comes from (module docstring); header values that
    are not positive numbers raise, and a header rate the rules' spans deny is said."""
    header = source.header
    spans = _rule_spans(windows, bomb)
    measured = float(np.median(spans)) if spans else None
    if header.get("playback_ticks") is not None or header.get("playback_time") is not None:
        ticks = _header_number(source, "playback_ticks")
        seconds = _header_number(source, "playback_time")
        rate, rule = _checked_rate(source.path, ticks / seconds), "the header's playback"
    elif header.get("tick_rate") is not None:
        rate = _checked_rate(source.path, _header_number(source, "tick_rate"))
        rule = "the header's tick_rate"
    elif measured is None:
        return CS2_TICK_RATE, "the header gives none, nor a round timed by the rules: CS2's 64"
    else:
        rate = min(KNOWN_TICK_RATES, key=lambda known: abs(math.log(measured / known)))
        rule = "the header gives none"
    if measured is not None:
        nearest = min(KNOWN_TICK_RATES, key=lambda known: abs(math.log(measured / known)))
        rule += (
            f"; {len(spans)} span(s) the rules time (bomb timer {BOMB_TIMER_S:g} s, round time "
            f"{ROUND_TIME_S:g} s) measure {measured:.1f} ticks/s"
            + ("" if nearest == rate else f": they deny {rate} (warning)")
        )
    return rate, rule


def _header_number(source: TableSource, key: str) -> float:
    """A header value that must be a positive finite number."""
    value = source.header.get(key)
    try:
        number = float(value)  # type: ignore[arg-type]
    except (TypeError, ValueError, OverflowError):
        number = math.nan
    is_number = isinstance(value, int | float) and not isinstance(value, bool)
    if not (is_number and math.isfinite(number) and number > 0):
        raise EstaError(f"{source.path}: header.json {key} {value!r:.40} is not a positive number")
    return number


def _rule_spans(windows: list[RoundWindow], bomb: pd.DataFrame) -> list[float]:
    """Ticks per second of each span the game's rules fix: plant to detonation, freeze end to
    the end of a round lost on time."""
    spans = [
        (w.end - w.freeze_end) / ROUND_TIME_S
        for w in windows
        if end_reason(w.reason) == "TargetSaved" and w.end > w.freeze_end
    ]
    events = bomb.sort_values("tick", kind="stable")
    plants = events.loc[events["event"].map(bomb_action) == "plant", "tick"].to_numpy(np.int64)
    blasts = events.loc[events["event"].map(bomb_action) == "explode", "tick"].to_numpy(np.int64)
    for blast in blasts:
        before = plants[plants < blast]
        if before.size:
            spans.append((blast - before[-1]) / BOMB_TIMER_S)
    return spans


def _checked_rate(path: Path, rate: float) -> int:
    """A tick rate a demo can have: 64 or 128 ticks a second, within 2%."""
    for known in KNOWN_TICK_RATES:
        if abs(rate - known) <= 0.02 * known:
            return known
    raise EstaError(f"{path}: a tick rate of {rate:g} ticks/s (a demo records 64 or 128)")


def _frame(source: TableSource, table: TableLayout) -> pd.DataFrame:
    """A whole (small) event table under the reader's names."""
    data = read_table(source, table.name, table.kinds, table.required)
    frame = _to_pandas(data.rename_columns([table.renames[c] for c in data.column_names]))
    _check_parts(source.path, frame, table.name)
    for column in ("tick", "start_tick"):
        if column in frame:
            frame[column] = _ticks(source.path, table.name, frame[column])
    return frame


MAX_TICK = 2**31 - 1
"""The largest tick a demo can reach (awpy writes ticks as int32)."""


def _ticks(path: Path, table: str, values: pd.Series) -> np.ndarray:
    """A tick column as int64; a null, fractional, negative or out-of-range tick raises."""
    numbers = pd.to_numeric(values, errors="coerce").to_numpy(dtype=np.float64, na_value=np.nan)
    with np.errstate(invalid="ignore"):
        bad = ~np.isfinite(numbers) | (numbers != np.round(numbers)) | (numbers < 0)
        bad |= numbers > MAX_TICK
    if bad.any():
        shown = values.iloc[int(np.flatnonzero(bad)[0])]
        raise EstaError(f"{path}: {table}: a row's tick {shown!s:.30} is not a tick of a demo")
    return numbers.astype(np.int64)


def _optional_frame(source: TableSource, table: TableLayout | None) -> pd.DataFrame | None:
    """A table the layout may lack (awpy 2 has no blinds; an awpy 3 folder may leave utility
    out): None where the source does not hold it."""
    if table is None or source.open_table(table.name) is None:
        return None
    return _frame(source, table)


def _damages(source: TableSource, layout: Layout) -> pd.DataFrame:
    """The damages table; awpy 3's HP and armour taken come from the values before and after."""
    frame = _frame(source, layout.damages)
    if "health_pre" in frame and "health_post" in frame:
        frame["dmg_health_taken"] = frame["health_pre"] - frame["health_post"]
    if "armor_pre" in frame and "armor_post" in frame:
        frame["dmg_armor_taken"] = frame["armor_pre"] - frame["armor_post"]
    return frame


def _rounds(source: TableSource, layout: Layout, bomb: pd.DataFrame) -> pd.DataFrame:
    """The rounds table under the reader's names; awpy 3's plants come from its bomb table."""
    rounds = _frame(source, layout.rounds)
    if len(rounds) > MAX_ROUNDS:
        raise EstaError(
            f"{source.path}: {len(rounds):,} rounds (a match holds at most {MAX_ROUNDS})"
        )
    for column in ("round_num", "start", "freeze_end", "end", "official_end", "bomb_plant"):
        if column not in rounds:
            continue
        values = pd.to_numeric(rounds[column], errors="coerce").to_numpy(np.float64)
        required = column in ("round_num", "start", "freeze_end", "end")
        given = np.ones(len(values), bool) if required else rounds[column].notna().to_numpy()
        with np.errstate(invalid="ignore"):
            wrong = ~np.isfinite(values) | (values != np.round(values)) | (values < 0)
            wrong |= values > MAX_TICK
        bad = wrong & given
        if bad.any():
            raw = rounds[column].iloc[int(np.flatnonzero(bad)[0])]
            shown = "null" if pd.isna(raw) else str(raw)
            raise EstaError(f"{source.path}: rounds: {column} {shown} is not a tick or number")
    if "official_end" not in rounds:
        rounds["official_end"] = pd.NA
    if "bomb_plant" in rounds:
        rounds["bomb_site"] = rounds.get("bomb_site", pd.Series("", index=rounds.index)).map(
            bomb_site
        )
        return rounds
    plants = bomb[bomb["event"].map(bomb_action) == "plant"].sort_values("tick", kind="stable")
    starts = rounds["start"].to_numpy(np.int64)
    ends = rounds["end"].to_numpy(np.int64)
    plant_tick: list[object] = []
    plant_site: list[str] = []
    for start, end in zip(starts, ends, strict=True):
        inside = plants[(plants["tick"] >= start) & (plants["tick"] <= end)]
        plant_tick.append(int(inside["tick"].iloc[0]) if len(inside) else pd.NA)
        plant_site.append(bomb_site(inside["site"].iloc[0]) if len(inside) else "")
    rounds["bomb_plant"] = pd.array(plant_tick, dtype="Int64")
    rounds["bomb_site"] = plant_site
    return rounds


def _holds_bomb(items: object) -> bool | None:
    """Whether awpy 2's `inventory` (demoparser2's names) holds the bomb; None where null."""
    if items is None or isinstance(items, float):
        return None
    return any(weapon_name(item, "display") == "C4" for item in items)  # type: ignore[attr-defined]


def _check_parts(path: Path, frame: pd.DataFrame, table: str) -> None:
    """A multipart demo's tables restart their ticks in each part: refused, named."""
    if "part" in frame:
        parts = sorted(int(p) for p in frame["part"].dropna().unique())
        if len(parts) > 1:
            raise EstaError(
                f"{path}: {table} holds parts {', '.join(map(str, parts))} of a multipart demo "
                "(ticks restart in each part): write each part's tables to its own folder"
            )


def _to_pandas(table: pa.Table) -> pd.DataFrame:
    """Arrow to pandas with nullable integers kept exact (steamids exceed float64's 2**53)."""
    exact = {pa.uint64(): pd.UInt64Dtype(), pa.int64(): pd.Int64Dtype()}
    return table.to_pandas(types_mapper=exact.get)
