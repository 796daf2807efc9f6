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
from decoy_cli.evaluate.run_tables import read_run_table
from decoy_cli.evaluate.runner import round_id
from decoy_cli.files import JsonObject, object_at, read_json_object
from decoy_cli.metrics import ALL_METRIC_NAMES
from decoy_cli.replay.view_trace import RoundTrace
from decoy_cli.text import shown_name, visible
from decoy_cli.view.page import (
    PageData,
    TableSpec,
    map_floor,
    player_table,
    round_entry,
    table_spec,
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
    for row in run.rounds.itertuples():
        label = f"{visible(str(row.match))}:{row.round}"
        key = keys.get(round_id(str(row.file_sha), int(row.round)))
        record = cache.load_round(key) if isinstance(key, str) else None
        if record is None:
            raise DecoyError(
                f"{folder}: the cached result of round {label} is missing or was written by "
                "another decoy version; run the same `decoy evaluate` into it again"
            )
        said = {k: _said(getattr(row, k)) for k in ("winner_original", "reason_original")}
        said |= {k: _said(getattr(row, k)) for k in ("winner_replay", "reason_replay")}
        info = (
            f"winner: data {said['winner_original']} ({said['reason_original']}), replay "
            f"{said['winner_replay']} ({said['reason_replay']}) · {row.frames} frames, "
            f"{float(row.seconds):.0f} s"
        )
        labels.append(f"{record.match_id}:{record.round_num}")
        traces.append(record.trace)
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
    return {
        "title": visible(f"decoy evaluate: {(cache_root or folder).resolve().name}"),
        "subtitle": f"{summary.get('data', '?')} data · {summary.get('mechanics', '')} · "
        f"{len(rounds)} rounds · map {options.get('map', '?')}",
        "map": map_floor(str(options.get("map") or _map_of(traces))),
        "tables": _tables(folder),
        "players": players,
        "rounds": rounds,
        "initial": 0,
    }


def _said(value: object) -> str:
    """A cell of rounds.csv as text; an empty one as "–"."""
    return "–" if pd.isna(value) else str(value)


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
