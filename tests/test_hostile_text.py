"""Text from data where it is shown (issue 35): control characters never reach a terminal, a
Markdown report or a CSV cell raw, and no CSV cell starts a spreadsheet formula; numbers are
written as they are."""

from __future__ import annotations

import builtins
import csv
import json
import re
import sys
from pathlib import Path
from typing import Any

import pandas as pd
import pytest
from esta_fixtures import make_match, write_match
from hypothesis import given, settings
from hypothesis import strategies as st
from typer.testing import CliRunner

from decoy_cli.cli import app
from decoy_cli.entry import main
from decoy_cli.evaluate.markdown import md_table
from decoy_cli.text import csv_cell, csv_inert, md_code, md_inline, visible

runner = CliRunner()
WIDE = {"COLUMNS": "400"}
NAME = '=HYPERLINK("http://x.invalid","\x1b[2Jclick")\u202e'
"""A player name: a formula, a clear-screen sequence and a direction override."""
MATCH_ID = "m\x1b]0;owned\x07\x9b31m"
"""A match id: an OSC title sequence, a bell and a C1 CSI."""
RAW = re.compile("[\x00-\x08\x0b-\x1f\x7f-\x9f\u202a-\u202e\u2066-\u2069]")
"""Control characters no output may hold (tab and newline are the outputs' own)."""


def _hostile_match(folder: Path, name: str = NAME) -> Path:
    document = make_match()
    document["matchID"] = MATCH_ID
    for game_round in document["gameRounds"]:
        for frame in game_round.get("frames") or []:
            for player in frame["t"]["players"]:
                if player["name"] == "t1":
                    player["name"] = name
    folder.mkdir(parents=True, exist_ok=True)
    return write_match(folder / "m.json", document)


def _cells(path: Path) -> list[str]:
    with path.open(newline="") as handle:
        return [cell for row in csv.reader(handle) for cell in [*row]]


# ---- the helpers --------------------------------------------------------------------------------


def test_visible_writes_every_control_character_as_an_escape() -> None:
    assert visible("a\x1b[2Jb\x07\x9b\u202ec\u2028") == "a\\x1b[2Jb\\x07\\x9b\\u202ec\\u2028"
    assert visible("line\nnext\x1b", keep="\n") == "line\nnext\\x1b"
    assert visible("plain café ✓") == "plain café ✓"
    assert not RAW.search(visible("".join(map(chr, range(0x20))) + "\x7f\x85\u2066"))


def test_markdown_text_cannot_make_links_columns_or_end_a_code_span() -> None:
    assert md_inline("[x](http://e) |a| <b>") == "\\[x\\](http://e) \\|a\\| \\<b\\>"
    assert md_inline("\x1b[31m") == "\\\\x1b\\[31m"  # shown as \x1b[31m
    assert md_code("a``b") == "```a``b```"
    assert md_code("`x`") == "`` `x` ``"
    table = md_table(["a", "b"], [[md_inline("p|q"), "r\x1bs\nt"]])
    assert table.splitlines()[-1] == "| p\\|q | r\\x1bs\\x0at |"


def test_csv_cells_that_would_start_a_formula_get_a_leading_quote() -> None:
    frame = pd.DataFrame(
        {
            "name": ["=1+1", "+cmd", "-x", "@SUM(A1)", "\tx", "\rx", "ok", "-1.5", "+2e3", None],
            "number": [-1.0, 2.0, -3.0, 4.0, 5.0, 6.0, 7.0, 8.0, 9.0, -10.0],
            "count": list(range(-5, 5)),
        }
    )
    inert = csv_inert(frame)
    assert list(inert["name"])[:9] == [
        "'=1+1",
        "'+cmd",
        "'-x",
        "'@SUM(A1)",
        "'\\x09x",
        "'\\x0dx",
        "ok",
        "-1.5",
        "+2e3",
    ] and pd.isna(inert["name"][9])
    assert inert["number"].equals(frame["number"]) and inert["count"].equals(frame["count"])
    assert list(csv_inert(pd.DataFrame(columns=["=a", "b"])).columns) == ["'=a", "b"]
    numbers = frame[["number", "count"]]
    assert csv_inert(numbers) is numbers  # nothing to change: the same frame


# ---- through the commands -----------------------------------------------------------------------


@pytest.mark.parametrize(
    "command",
    [
        ["info", "{file}"],
        ["info", "{file}:1"],
        ["info", "{folder}"],
        ["replay", "{file}:1", "--models", "none", "--out", "{tmp}/replay"],
        ["evaluate", "{folder}", "--no-combat", "--out", "{tmp}/ev"],
        ["snap", "{file}:1", "--metrics"],
    ],
)
def test_no_control_character_from_the_data_reaches_the_terminal(
    tmp_path: Path, command: list[str]
) -> None:
    file = _hostile_match(tmp_path / "in")
    args = [part.format(file=file, folder=file.parent, tmp=tmp_path) for part in command]
    result = runner.invoke(app, args, env=WIDE)
    assert result.exit_code in (0, 1) and "Traceback" not in result.output, result.output
    assert not RAW.search(result.output), repr(result.output)
    if command[0] in ("info", "replay") and command[1].endswith(":1"):
        assert "\\x1b[2Jclick" in result.stdout  # shown, as an escape


def test_an_error_line_shows_a_file_name_s_control_characters(tmp_path: Path) -> None:
    missing = tmp_path / "gone\x1b[2J\u202e.json"
    result = runner.invoke(app, ["info", str(missing)], env=WIDE)
    assert result.exit_code == 1
    assert not RAW.search(result.stderr)
    assert result.stderr.startswith("error: ") and "gone\\x1b[2J\\u202e.json" in result.stderr
    assert len(result.stderr.strip().splitlines()) == 1


def test_replay_files_are_inert_and_hold_no_control_character(tmp_path: Path) -> None:
    file = _hostile_match(tmp_path / "in")
    out = tmp_path / "replay"
    result = runner.invoke(app, ["replay", f"{file}:1", "--models", "none", "--out", str(out)])
    assert result.exit_code == 0, result.output
    for name in ("replay.csv", "events.csv", "players.csv"):
        cells = _cells(out / name)
        assert not any(cell.startswith(("=", "+", "@", "\t", "\r")) for cell in cells), name
        assert not any(RAW.search(cell) for cell in cells), name
    players = _cells(out / "replay.csv")
    assert "'" + visible(NAME) in players
    assert "-" not in [c[:1] for c in players if not re.fullmatch(r"-?[\d.e+-]+", c)]
    summary: dict[str, Any] = json.loads((out / "summary.json").read_text())
    assert summary["match_id"] == MATCH_ID  # JSON keeps the data, its controls escaped
    assert not RAW.search((out / "summary.json").read_text())


def test_evaluate_tables_and_report_are_inert(tmp_path: Path) -> None:
    folder = tmp_path / "in\x1b[2J"
    file = _hostile_match(folder)
    (folder / "broken\x1b[31m=1.json").write_text("{")
    out = tmp_path / "ev"
    result = runner.invoke(app, ["evaluate", str(folder), "--no-combat", "--out", str(out)])
    assert result.exit_code == 1, result.output  # the broken file is a recorded failure
    for path in out.rglob("*.csv"):
        cells = _cells(path)
        assert not any(cell.startswith(("=", "+", "@", "\t", "\r")) for cell in cells), path
        assert not any(RAW.search(cell) for cell in cells), path
    assert "'" + visible(NAME) in _cells(out / "players.csv")
    assert file.exists()
    report = (out / "report.md").read_text()
    assert not RAW.search(report)
    assert "broken\\\\x1b\\[31m=1.json" in report  # escaped for Markdown: shows broken\x1b[31m


# ---- property: any text ------------------------------------------------------------------------

ANY_TEXT = st.text(
    alphabet=st.characters(codec="utf-8", exclude_categories=("Cs",)), max_size=40
) | st.sampled_from(["=1+1", "-", "+", "@", "\t", "\r", "\x1b[2J", "\u202e", "|", "`"])


@settings(max_examples=300, deadline=None)
@given(text=ANY_TEXT)
def test_any_text_is_shown_without_control_characters(text: str) -> None:
    for shown in (visible(text), md_inline(text), md_code(text), str(csv_cell(text))):
        assert not RAW.search(shown) and "\n" not in shown and "\u2028" not in shown
    cell = str(csv_cell(text))
    number = re.fullmatch(r"[+-]?(\d+\.?\d*|\.\d+)([eE][+-]?\d+)?", cell)
    assert not cell.startswith(("=", "+", "-", "@", "\t", "\r")) or number  # numbers as they are
    assert re.search(r"(?<!\\)\|", md_inline(text)) is None  # no bare "|": no new column
    assert visible(visible(text)) == visible(text)  # an escape is shown as it is


def test_a_ctrl_c_while_the_application_loads_is_one_line(
    monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    real_import = builtins.__import__

    def interrupted(name: str, *args: Any, **kwargs: Any) -> Any:
        if name == "decoy_cli.cli":
            raise KeyboardInterrupt  # the user's Ctrl-C while the libraries load
        return real_import(name, *args, **kwargs)

    monkeypatch.delitem(sys.modules, "decoy_cli.cli", raising=False)
    monkeypatch.setattr(builtins, "__import__", interrupted)
    with pytest.raises(SystemExit) as stopped:
        main()
    assert stopped.value.code == 130
    assert capsys.readouterr().err == "interrupted while starting: nothing was done\n"
