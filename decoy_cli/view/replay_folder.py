"""The view page of a `decoy replay` output folder (decoy_cli/view/page.py): its summary as a
table, its players and the round's paths and events (`trace.json`).

A folder that is not a replay, lacks a file, or was written by a decoy that wrote no
`trace.json` is a DecoyError with one line.
"""

from __future__ import annotations

from pathlib import Path

import msgspec
import pandas as pd

from decoy_cli.errors import DecoyError
from decoy_cli.files import JsonObject, object_at, read_json_object
from decoy_cli.metrics import ALL_METRIC_NAMES
from decoy_cli.reading import read_csv_table, read_limited
from decoy_cli.replay.output import TRACE_FILE
from decoy_cli.replay.view_trace import RoundTrace
from decoy_cli.text import shown_name, visible
from decoy_cli.view.page import (
    PageData,
    map_floor,
    player_table,
    round_entry,
    table_spec,
    winner_info,
)

REPLAY_MARKER = "replay.csv"
"""The file that tells a replay's folder from an evaluate run's."""

PLAYER_COLUMNS = ("player", "side", "death")
MAX_TRACE_BYTES = 256_000_000
"""Largest `trace.json` read: a round's thinned paths take a few hundred kB."""
MAX_PLAYERS_MB = 64
"""Largest players.csv of a replay read: it holds one row a player."""


def is_replay_folder(folder: Path) -> bool:
    return (folder / REPLAY_MARKER).is_file()


def replay_page(folder: Path) -> PageData:
    """The page's data of the replay in `folder`."""
    summary = read_json_object(folder / "summary.json", "`decoy replay`")
    trace_path = folder / TRACE_FILE
    if not trace_path.is_file():
        raise DecoyError(
            f"{folder}: written by an older decoy (no {TRACE_FILE}); run the same "
            "`decoy replay` again"
        )
    try:
        trace = msgspec.json.decode(read_limited(trace_path, MAX_TRACE_BYTES), type=RoundTrace)
    except (OSError, msgspec.DecodeError) as error:
        raise DecoyError(f"{trace_path}: not a round's trace ({error})") from None
    players = read_csv_table(folder / "players.csv", limit_mb=MAX_PLAYERS_MB, text=("player",))
    metrics = [m for m in ALL_METRIC_NAMES if m in players.columns]
    columns = [*PLAYER_COLUMNS, *metrics, "late_share", "stuck", "reason"]
    missing = [c for c in columns if c not in players.columns]
    if missing or len(players) != len(trace.players):
        raise DecoyError(f"{folder / 'players.csv'}: not the players of {trace_path.name}")
    label = visible(f"{summary.get('match_id', '?')}:{summary.get('round_num', '?')}")
    original, replay = object_at(summary, "outcome_original"), object_at(summary, "outcome_replay")
    sides = {p.side for p in trace.players}
    winners = (original.get("winner"), original.get("reason"), replay.get("winner"))
    frames = summary.get("frames", "?")
    info = f"{winner_info(*winners, replay.get('reason'), sides)} · {frames} frames"
    table = player_table(players[columns], [0] * len(players), list(range(len(players))))
    for row, player in zip(table["rows"], trace.players, strict=True):
        row[0] = shown_name(player.name)  # as recorded, not as the CSV made it inert
    return {
        "title": f"decoy replay: {label}",
        "subtitle": visible(f"{folder.resolve().name} · map {trace.map_name}"),
        "map": map_floor(trace.map_name),
        "tables": [table_spec("The replay", _summary_rows(summary))],
        "players": table,
        "rounds": [round_entry(label, info, trace)],
        "initial": 0,
        "heat": None,
    }


def _summary_rows(summary: JsonObject) -> pd.DataFrame:
    """The summary's values, one row each (a dict's values as `name.key`)."""
    rows = []
    for name, value in summary.items():
        items = value.items() if isinstance(value, dict) else [("", value)]
        for key, item in items:
            text = ", ".join(map(str, item)) if isinstance(item, list) else item
            rows.append((f"{name}.{key}" if key else name, text))
    return pd.DataFrame(rows, columns=["what", "value"])
