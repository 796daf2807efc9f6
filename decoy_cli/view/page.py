"""The view page: one HTML file holding its data, script and style (no server, no network).

`write_page` fills the slots of page.html with page.css, the script and the page's data as JSON.
The JSON is written so that no text from the data can end its script element or start markup
(`<`, `>`, `&` and the line separators as `\\u` escapes), and the script shows every text
through `textContent` or the canvas, never as markup. Escaping is the first protection; the
page's Content-Security-Policy (`policy`) is the second: it allows the page's one script and
one style by their SHA-256 and nothing else (no inline handler, no other script, no network),
so markup injected into the page could not run.

The data (`PageData`): `title`, `subtitle`, `map` (`map_floor`), `tables` (each `title`,
`columns`, `rows`), `players` (the player-round list: `columns`, `rows`, and per row the index
of its `round` and of its `player` in that round), `rounds` (each `label`, `info` and a
`RoundTrace` as a dict), `initial` (the round shown first) and `heat` (the run's heatmaps,
`HeatLayer`, or null).

The script is the files of `SCRIPTS` in their order inside one function: data.js decodes a
round, draw.js draws the map, controls.js answers the controls, the keys and the URL, tables.js
fills the tables and starts the page.
"""

from __future__ import annotations

import base64
import hashlib
import json
import math
from functools import cache
from pathlib import Path
from typing import TypedDict

import msgspec
import numpy as np
import pandas as pd

from decoy_cli.errors import DecoyError
from decoy_cli.files import JsonObject, json_ready, write_atomic
from decoy_cli.replay.view_trace import RoundTrace
from decoy_cli.text import shortened, shown_name, visible

Cell = str | int | float | bool | None
"""A cell of a page's table."""


class TableSpec(TypedDict):
    """A table of the page."""

    title: str
    columns: list[str]
    rows: list[list[Cell]]


class PlayerTable(TableSpec):
    """The player-round list: a table, its columns' readable names, and per row the index of
    its round and of its player."""

    labels: list[str]
    round: list[int]
    player: list[int]


class MapFloor(TypedDict):
    """A map's nav areas as the page draws them (`map_floor`), and its places' labels."""

    name: str
    areas: list[int]
    places: list[list[int | str]]


class HeatLayer(TypedDict):
    """The run's heatmaps on a grid: cell (i, j) spans x0 + i·cell, y0 + j·cell (decimetres);
    `real` and `replay` the position samples per cell as a flat list of (j·nx + i, count)."""

    x0: int
    y0: int
    cell: int
    nx: int
    real: list[int]
    replay: list[int]


class PageData(TypedDict):
    """What the page shows (module docstring)."""

    title: str
    subtitle: str
    map: MapFloor
    tables: list[TableSpec]
    players: PlayerTable
    rounds: list[JsonObject]
    initial: int
    heat: HeatLayer | None


COLUMN_LABELS = {
    "death": "replay death: how",
    "hp_rmse": "HP RMSE (HP)",
    "mean_dist": "mean distance (m)",
    "rmse": "RMSE (m)",
    "max_dist": "largest distance (m)",
    "dtw": "DTW (m)",
    "frechet_2d": "Fréchet 2-D (m)",
    "final_dist": "final distance (m)",
    "paper_euclidean": "paper: Euclidean (m)",
    "paper_rmse": "paper: RMSE (m)",
    "paper_dtw": "paper: DTW (m)",
    "paper_frechet_2d": "paper: Fréchet 2-D (m)",
    "paper_dtw_fastdtw": "paper: DTW by fastdtw (m)",
    "late_share": "late (share of frames)",
    "stuck": "stuck (episodes)",
    "reason": "not evaluated: why",
}
"""Readable names, with units, of the player-round list's columns (docs/metrics.md); a column
not named here shows its own name. The column's own name is the header's tooltip."""

TEXT_CELL_LIMIT = 200
"""Characters of a text cell of the page's tables (a reason, a list of names: any longer is
cut with a marker)."""

SCRIPTS = ("data.js", "draw.js", "controls.js", "tables.js")
"""The script's files, in the order the page runs them (module docstring)."""

_HERE = Path(__file__).resolve().parent
_ESCAPES = {
    "<": "\\u003c",
    ">": "\\u003e",
    "&": "\\u0026",
    "\u2028": "\\u2028",
    "\u2029": "\\u2029",
}


def embedded_json(data: object) -> str:
    """`data` as strict JSON that is inert inside an HTML script element."""
    text = json.dumps(json_ready(data), separators=(",", ":"), allow_nan=False)
    for char, escape in _ESCAPES.items():
        text = text.replace(char, escape)
    return text


def policy(script: str, style: str) -> str:
    """The page's Content-Security-Policy: its one inline `script` and `style` by hash, images
    only from data: URLs (the canvas), nothing else (no other script, no inline handler, no
    request, no form, no base URL)."""
    return (
        f"default-src 'none'; script-src {_sha256(script)}; style-src {_sha256(style)}; "
        "img-src data:; base-uri 'none'; form-action 'none'"
    )


def _sha256(text: str) -> str:
    """A CSP source naming `text` by its SHA-256 (of its UTF-8 bytes, as browsers hash it)."""
    return f"'sha256-{base64.b64encode(hashlib.sha256(text.encode('utf-8')).digest()).decode()}'"


def page_html(data: PageData) -> str:
    """The page's HTML with everything inline."""
    html = (_HERE / "page.html").read_text(encoding="utf-8")
    style = (_HERE / "page.css").read_text(encoding="utf-8")
    script = page_script()
    parts = {
        "/*POLICY*/": policy(script, style),
        "/*STYLE*/": style,
        "/*SCRIPT*/": script,
        "/*DATA*/": embedded_json(data),
    }
    for slot, text in parts.items():  # each slot once, in the order of the page
        head, _, tail = html.partition(slot)
        html = head + text + tail
    return html


def page_script() -> str:
    """The page's one script: the files of `SCRIPTS` inside one strict function."""
    parts = [(_HERE / name).read_text(encoding="utf-8") for name in SCRIPTS]
    return '"use strict";\n(function () {\n' + "\n".join(parts) + "})();\n"


def write_page(path: str | Path, data: PageData) -> Path:
    """Write the page atomically; a full disk or a refused path raises OutputError."""
    return write_atomic(path, page_html(data).encode("utf-8"))


@cache
def map_floor(map_name: str) -> MapFloor:
    """The map's floor for the page: its nav areas as one flat list of (x_min, y_min, x_max,
    y_max, mean height) in decimetres, lowest first (an upper floor is drawn over a lower)."""
    from decoy_cli.csgo import HAMMER_TO_M
    from decoy_cli.world.navmesh import load_navmesh

    nav = load_navmesh(map_name)
    z = (nav.z_at_min + nav.z_at_max) / 2
    rows = np.column_stack([nav.x_min, nav.y_min, nav.x_max, nav.y_max, z]) * HAMMER_TO_M * 10
    places: list[list[int | str]] = []
    size = (rows[:, 2] - rows[:, 0]) * (rows[:, 3] - rows[:, 1])
    for place in nav.places:  # each at the centre of its largest area: always on its floor
        largest = int(np.argmax(np.where(nav.place == place, size, -1.0)))
        x_min, y_min, x_max, y_max = rows[largest, :4]
        places.append([round((x_min + x_max) / 2), round((y_min + y_max) / 2), place])
    rows = rows[np.argsort(rows[:, 4], kind="stable")]
    areas = np.rint(rows).astype(np.int64).reshape(-1).tolist()
    return {"name": map_name, "areas": areas, "places": places}


def round_entry(label: str, info: str, trace: RoundTrace) -> JsonObject:
    """One round of the page: its label, a line about it and its trace, the players' names
    with their control characters written as escapes and cut to a readable length
    (`decoy_cli.text.shown_name`)."""
    recorded = msgspec.to_builtins(trace)
    for player in recorded["players"]:
        player["name"] = shown_name(player["name"])
    recorded["weapons"] = [shown_name(w) for w in recorded["weapons"]]
    return {"label": visible(label), "info": visible(info), **recorded}


def table_spec(title: str, frame: pd.DataFrame, digits: int = 4) -> TableSpec:
    """A table of the page: its columns and rows, numbers rounded to `digits` significant
    digits, missing values as null."""
    rows = [[_cell(v, digits) for v in row] for row in frame.itertuples(index=False)]
    return {"title": title, "columns": [str(c) for c in frame.columns], "rows": rows}


def player_table(frame: pd.DataFrame, rounds: list[int], players: list[int]) -> PlayerTable:
    """The player-round list of `frame`, row k the player `players[k]` of round `rounds[k]`."""
    spec = table_spec("", frame)
    labels = [COLUMN_LABELS.get(c, c) for c in spec["columns"]]
    return {**spec, "labels": labels, "round": rounds, "player": players}


def _cell(value: object, digits: int) -> Cell:
    if isinstance(value, np.generic):
        value = value.item()
    if value is None or value is pd.NA:
        return None
    if isinstance(value, bool):
        return value
    if isinstance(value, int):
        return value
    if isinstance(value, float):
        if not math.isfinite(value):
            return None
        return float(f"{value:.{digits}g}")
    return shortened(str(value), TEXT_CELL_LIMIT)


def winner_info(
    winner_data: object,
    reason_data: object,
    winner_replay: object,
    reason_replay: object,
    sides: set[str],
) -> str:
    """The round's winner in the data and in the replay, in words: a winner not recorded (or
    not decided: a round of one side's players has none in the replay) is said, not dashed."""

    def said(who: str, winner: object, reason: object) -> str:
        if pd.isna(winner) or not str(winner):
            return f"{who}: none"
        return f"{who}: {winner}" + ("" if pd.isna(reason) else f" ({reason})")

    data, replay = (
        said("data", winner_data, reason_data),
        said("replay", winner_replay, reason_replay),
    )
    text = f"winner {data}, {replay}"
    if len(sides) == 1:
        text += f" (only the {next(iter(sides))} side's players are in the data)"
    return text


def round_index(data: PageData, label: str) -> int:
    """The index of the round labelled `label` ("MATCH:ROUND"); a DecoyError naming a few of
    the labels when there is none."""
    labels = [str(r["label"]) for r in data["rounds"]]
    if label in labels:
        return labels.index(label)
    shown = ", ".join(labels[:3]) + (", ..." if len(labels) > 3 else "")
    raise DecoyError(f"no round {label} in this page's {len(labels)} rounds ({shown or 'none'})")
