"""The view page of an `evaluate` run (decoy_cli/view/page.py): the run's tables, its
player-rounds and every round's paths and events, read from the run's folder and its cache.

A folder that is not a run, lacks a file, or was written by a decoy whose cache holds no paths
is a DecoyError with one line.
"""

from __future__ import annotations

from pathlib import Path

import pandas as pd

from decoy_cli.errors import DecoyError
from decoy_cli.evaluate.cache import RunCache
from decoy_cli.evaluate.compare import read_run
from decoy_cli.evaluate.heat import HeatGrid, read_grid_sums
from decoy_cli.evaluate.record import RoundRecord
from decoy_cli.evaluate.run_tables import read_run_table
from decoy_cli.evaluate.runner import round_id
from decoy_cli.files import JsonObject, object_at, read_json_object
from decoy_cli.metrics import ALL_METRIC_NAMES
from decoy_cli.replay.view_trace import RoundTrace
from decoy_cli.text import shown_name, visible
from decoy_cli.view.page import (
    HeatLayer,
    PageData,
    TableSpec,
    map_floor,
    player_table,
    round_entry,
    table_spec,
    winner_info,
)

TABLES = (
    ("trajectory", "Trajectory fidelity (metres): both protocols, by side"),
    ("combat", "HP, deaths and outcomes"),
    ("death_counts", "Deaths: data against replay"),
    ("outcome_winner_confusion", "Winner: data (rows) against replay (columns)"),
    ("outcome_reason_confusion", "End reason: data (rows) against replay (columns)"),
    ("bomb", "The bomb"),
    ("bomb_plant_confusion", "Plants: data (rows) against replay (columns)"),
    ("bomb_defuse_confusion", "Defuses: data (rows) against replay (columns)"),
    ("places", "Where the replay is off most (nav places)"),
    ("unevaluated", "Player-rounds not evaluated, and why"),
)
"""The tables of tables/ the page shows (those of report.md), in its order."""

PLAYER_COLUMNS = ("match", "round", "player", "side", "death", "hp_rmse")
"""The player-round list's columns before the trajectory metrics; `late_share`, `stuck` and
`reason` follow them."""

HEAT_FACTOR = 4
"""Cells of the run's heat grid (decoy_cli/evaluate/heat.py) per side of a cell of the page's
heatmap: a coarser grid keeps the page small."""


def run_page(folder: Path, cache_root: Path | None = None) -> PageData:
    """The page's data of the run in `folder`; its cache is under `cache_root` (default: the
    folder; evaluate writes the page into a staging folder beside the cache)."""
    run = read_run(folder)
    summary = read_json_object(folder / "summary.json", "`decoy evaluate`")
    keys = summary.get("cache_keys")
    if not isinstance(keys, dict):
        raise DecoyError(
            f"{folder}: written by an older decoy (its summary.json names no cached rounds); "
            "run the same `decoy evaluate` into it again"
        )
    if len(run.rounds) and not pd.api.types.is_integer_dtype(run.rounds["round"]):
        raise DecoyError(f"{folder / 'rounds.csv'}: a row without a round number")
    cache = RunCache(cache_root or folder)
    rounds: list[JsonObject] = []
    labels: list[str] = []
    traces: list[RoundTrace] = []
    records: list[RoundRecord] = []
    for row in run.rounds.itertuples():
        label = f"{visible(str(row.match))}:{row.round}"
        key = keys.get(round_id(str(row.file_sha), int(row.round)))
        record = cache.load_round(key) if isinstance(key, str) else None
        if record is None:
            raise DecoyError(
                f"{folder}: the cached result of round {label} is missing or was written by "
                "another decoy version; run the same `decoy evaluate` into it again"
            )
        sides = {p.side for p in record.trace.players}
        winners = (row.winner_original, row.reason_original, row.winner_replay)
        info = (
            f"{winner_info(*winners, row.reason_replay, sides)} · {row.frames} frames, "
            f"{float(row.seconds):.0f} s"
        )
        labels.append(f"{record.match_id}:{record.round_num}")
        traces.append(record.trace)
        records.append(record)
        rounds.append(round_entry(labels[-1], info, record.trace))
    metrics = [m for m in ALL_METRIC_NAMES if m in run.players.columns]
    columns = [*PLAYER_COLUMNS, *metrics, "late_share", "stuck", "reason"]
    missing = [c for c in columns if c not in run.players.columns]
    if missing:
        raise DecoyError(f"{folder / 'players.csv'}: lacks the columns {', '.join(missing)}")
    players = player_table(run.players[columns], *_player_rows(folder, run.players, labels, traces))
    for row, r, p in zip(players["rows"], players["round"], players["player"], strict=True):
        # match and player (PLAYER_COLUMNS) as recorded, not as the CSV made them inert
        row[0] = visible(labels[r]).rsplit(":", 1)[0]
        row[2] = shown_name(traces[r].players[p].name)
    options = object_at(summary, "options")
    map_name = str(options.get("map") or _map_of(traces))
    return {
        "title": visible(f"decoy evaluate: {_named(summary, cache_root or folder)}"),
        "subtitle": f"{summary.get('data', '?')} data · {summary.get('mechanics', '')} · "
        f"{len(rounds)} rounds · map {options.get('map', '?')}",
        "map": map_floor(map_name),
        "tables": _tables(folder),
        "players": players,
        "rounds": rounds,
        "initial": 0,
        "heat": heat_layer(map_name, records),
    }


def _named(summary: JsonObject, folder: Path) -> str:
    """What the run evaluated: its inputs' names (a few), else its folder's name."""
    inputs = summary.get("inputs")
    names = [Path(str(p)).name for p in inputs] if isinstance(inputs, list) else []
    if not names:
        return folder.resolve().name
    more = f" and {len(names) - 2} more" if len(names) > 2 else ""
    return ", ".join(names[:2]) + more


def heat_layer(map_name: str, records: list[RoundRecord]) -> HeatLayer | None:
    """The run's heatmaps (the position samples of every round's record, real and replayed)
    on a grid `HEAT_FACTOR` times coarser than the run's, or None without a round."""
    if not records:
        return None
    grid = HeatGrid.for_map(map_name)
    nx = -(-grid.nx // HEAT_FACTOR)
    layer: HeatLayer = {
        "x0": round(grid.x0 * 10),
        "y0": round(grid.y0 * 10),
        "cell": round(grid.cell * HEAT_FACTOR * 10),
        "nx": nx,
        "real": [],
        "replay": [],
    }
    for name in ("real", "replay"):
        totals: dict[int, int] = {}
        for record in records:
            cells, counts = read_grid_sums(
                record.heat_original if name == "real" else record.heat_replay
            )
            coarse = (cells // grid.nx // HEAT_FACTOR) * nx + (cells % grid.nx) // HEAT_FACTOR
            for cell, count in zip(coarse.tolist(), counts.tolist(), strict=True):
                totals[cell] = totals.get(cell, 0) + count
        layer[name] = [v for cell in sorted(totals) for v in (cell, totals[cell])]
    return layer


def _map_of(traces: list[RoundTrace]) -> str:
    return str(traces[0].map_name) if traces else "de_dust2"


def _player_rows(
    folder: Path, players: pd.DataFrame, labels: list[str], traces: list[RoundTrace]
) -> tuple[list[int], list[int]]:
    """The round and player index of each players.csv row: its rows follow the rounds of
    rounds.csv (`labels`, `traces`), each round's players in their order
    (decoy_cli/evaluate/tables.py)."""
    round_of, player_of = [], []
    for index, trace in enumerate(traces):
        for p in range(len(trace.players)):
            round_of.append(index)
            player_of.append(p)
    numbers = [int(labels[r].rsplit(":", 1)[1]) for r in round_of]
    if pd.to_numeric(players["round"], errors="coerce").tolist() != numbers:
        raise DecoyError(
            f"{folder / 'players.csv'}: its rows are not the players of the cached rounds "
            "(an edited file, or a folder of two runs); run `decoy evaluate` into it again"
        )
    return round_of, player_of


def _tables(folder: Path) -> list[TableSpec]:
    tables = []
    for name, title in TABLES:
        path = folder / "tables" / f"{name}.csv"
        if not path.exists():
            raise DecoyError(f"{path}: not found (an incomplete `decoy evaluate` output)")
        frame = read_run_table(path)
        if len(frame):
            tables.append(table_spec(title, frame))
    return tables
