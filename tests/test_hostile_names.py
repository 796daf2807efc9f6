"""A very long name from the data (issue 51): a 100,000-character player name is shown cut to
`NAME_LIMIT` characters with a marker where it is drawn (the figure's legend, the terminal's
tables, the view page) and kept whole in the CSV files; no output grows with it beyond the
name itself. Sizes are compared, not times."""

from __future__ import annotations

import json
import re
from pathlib import Path
from typing import Any

import pandas as pd
import pytest
from esta_fixtures import make_match, write_match
from PIL import Image
from typer.testing import CliRunner

from decoy_cli.cli import app
from decoy_cli.text import CUT_MARK, NAME_LIMIT

runner = CliRunner()
Image.MAX_IMAGE_PIXELS = None  # a figure as large as a long name once made it: measured, not drawn
LONG = "N" * 100_000
SHOWN = LONG[: NAME_LIMIT - 1] + CUT_MARK


def named(folder: Path, name: str) -> Path:
    """The fixture match with player t3 (alive in round 2: in the figure's legend) named
    `name`."""
    document = make_match()
    for game_round in document["gameRounds"]:
        for frame in game_round.get("frames") or []:
            for player in frame["t"]["players"]:
                if player["name"] == "t3":
                    player["name"] = name
    folder.mkdir(parents=True)
    return write_match(folder / "m.json", document)


@pytest.fixture(scope="module")
def replays(tmp_path_factory: pytest.TempPathFactory) -> dict[str, tuple[Path, str]]:
    """The replay folder and the terminal output of round 2, with a short and a long name."""
    done = {}
    for key, name in (("short", "t1"), ("long", LONG)):
        folder = tmp_path_factory.mktemp(key)
        out = folder / "replay"
        args = ["replay", f"{named(folder / 'in', name)}:2", "--models", "none", "--out", str(out)]
        result = runner.invoke(app, args, env={"COLUMNS": "400"})
        assert result.exit_code == 0, result.output[:2000]
        done[key] = (out, result.stdout)
    return done


def test_the_figure_does_not_grow_with_a_name(replays: dict[str, tuple[Path, str]]) -> None:
    short, long = (Image.open(replays[k][0] / "paths.png").size for k in ("short", "long"))
    assert long[1] == short[1] and long[0] <= short[0] + 400, (short, long)


def test_the_terminal_shows_a_long_name_cut(replays: dict[str, tuple[Path, str]]) -> None:
    short, long = replays["short"][1], replays["long"][1]
    assert SHOWN in long and LONG[:NAME_LIMIT] not in long
    # a table's column widens by at most the name cut, on each line of the table
    assert len(long) <= len(short) + NAME_LIMIT * long.count("\n")


def test_the_csv_files_keep_the_name_whole(replays: dict[str, tuple[Path, str]]) -> None:
    folder = replays["long"][0]
    players = pd.read_csv(folder / "players.csv")
    assert LONG in players["player"].tolist()
    assert LONG in set(pd.read_csv(folder / "replay.csv")["player"])


def test_the_page_shows_a_long_name_cut(replays: dict[str, tuple[Path, str]]) -> None:
    pages = {}
    for key in ("short", "long"):
        folder = replays[key][0]
        result = runner.invoke(app, ["view", str(folder), "--out", str(folder / "page.html")])
        assert result.exit_code == 0, result.output
        pages[key] = (folder / "page.html").read_text(encoding="utf-8")
    assert LONG[:NAME_LIMIT] not in pages["long"]
    data = page_data(pages["long"])
    assert SHOWN in [p["name"] for p in data["rounds"][0]["players"]]
    assert SHOWN in [row[0] for row in data["players"]["rows"]]
    # the name, cut, is in the page twice (the round's players, the player table)
    assert len(pages["long"]) < len(pages["short"]) + 2 * len(json.dumps(SHOWN))


def page_data(html: str) -> dict[str, Any]:
    found = re.search(r'<script type="application/json" id="data">(.*?)</script>', html, re.S)
    assert found is not None
    return json.loads(found.group(1))


def test_a_name_matplotlib_would_read_as_math_is_drawn_as_it_is(tmp_path: Path) -> None:
    file = named(tmp_path / "in", "$\\notacommand{$")
    out = tmp_path / "replay"
    result = runner.invoke(app, ["replay", f"{file}:2", "--models", "none", "--out", str(out)])
    assert result.exit_code == 0, result.output
    assert (out / "paths.png").stat().st_size > 0
