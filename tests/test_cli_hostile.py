"""Hostile input through the commands (issue 17): a clean `error:` line or a recorded failure,
never a traceback; text from the data is printed as it is; outputs checked before long work;
a damaged cache counts as missing; implausible data fails or is replayed with warnings."""

from __future__ import annotations

import csv
import json
import os
import shutil
from pathlib import Path
from typing import Any

import pytest
from esta_fixtures import make_match, write_match
from esta_mutations import byte_damage, compression, damaged_file, mutations
from hypothesis import HealthCheck, given, settings
from typer.testing import CliRunner

from decoy_cli.cli import app

runner = CliRunner()
WIDE = {"COLUMNS": "220"}
MARKUP = "[/bold]x[red]"
"""Text rich would read as markup (a closing tag that opens nothing stops rich with an error)."""


def _invoke(*args: str):
    return runner.invoke(app, list(args), env=WIDE)


def _write(path: Path, document: dict[str, Any]) -> Path:
    path.parent.mkdir(parents=True, exist_ok=True)
    return write_match(path, document)


def _clean_end(result) -> None:
    """Exit 0, or exit 1 with one `error:` line last on stderr; never a traceback or a bug."""
    assert "Traceback" not in result.output and "internal error" not in result.output, result.output
    assert result.exit_code in (0, 1), result.output
    if result.exit_code == 1:
        assert result.stderr.strip().splitlines()[-1].startswith("error: "), result.stderr


def _rows(path: Path) -> list[dict[str, str]]:
    with path.open(newline="") as handle:
        return list(csv.DictReader(handle))


# ---- text from the data is printed, never read as markup ---------------------------------------


def _markup_match(tmp_path: Path) -> Path:
    document = make_match()
    document["matchID"] = MARKUP
    for game_round in document["gameRounds"]:
        for frame in game_round.get("frames") or []:
            for player in frame["t"]["players"]:
                if player["name"] == "t1":
                    player["name"] = MARKUP
    return _write(tmp_path / f"in{MARKUP}" / "m.json", document)


@pytest.mark.parametrize(
    "command",
    [
        ["replay", "{file}:1", "--models", "none", "--out", "{tmp}/replay"],
        ["info", "{file}"],
        ["info", "{file}:1"],
        ["info", "{folder}"],
        ["snap", "{file}:1", "--metrics", "--worst", "3"],
        ["snap", "{file}"],
    ],
)
def test_names_from_the_data_are_printed_as_they_are(tmp_path: Path, command: list[str]) -> None:
    file = _markup_match(tmp_path)
    args = [part.format(file=file, folder=file.parent, tmp=tmp_path) for part in command]
    result = _invoke(*args)
    _clean_end(result)
    assert MARKUP in result.output


def test_a_failure_message_with_markup_is_printed_as_it_is(tmp_path: Path) -> None:
    """evaluate lists failures in the terminal: a file name with markup in it is shown whole."""
    file = _markup_match(tmp_path)
    broken = file.parent / "broken.json"
    broken.write_text("{")
    result = _invoke(
        "evaluate", str(file.parent), "--no-combat", "--no-figures", "--out", str(tmp_path / "out")
    )
    _clean_end(result)
    assert result.exit_code == 1
    assert f"in{MARKUP}" in result.stdout.replace("\n", "")


# ---- output paths are checked before the long work ---------------------------------------------


@pytest.mark.parametrize(
    "command",
    [
        ["models", "import-decoy", "{missing}", "--out", "{file}"],
        ["download", "abc", "--dest", "{file}", "--base-url", "http://127.0.0.1:9"],
        ["train", "dip", "{missing}", "--out", "{file}"],
        ["train", "dog", "{missing}", "--out", "{file}"],
        ["make-sample", "--out", "{file}", "--rounds", "1"],
    ],
)
def test_an_output_folder_that_is_a_file_is_refused_first(
    tmp_path: Path, command: list[str]
) -> None:
    """The output check comes before any input is read, trained or played: the error names the
    output, although the input is missing too."""
    taken = tmp_path / "taken"
    taken.write_text("a file, not a folder")
    args = [part.format(file=taken, missing=tmp_path / "missing") for part in command]
    result = _invoke(*args)
    assert result.exit_code == 1, result.output
    assert result.stderr.strip() == f"error: cannot write into {taken}: it is a file, not a folder"


# ---- the cache ---------------------------------------------------------------------------------


def test_a_cache_record_under_another_key_counts_as_missing(tmp_path: Path) -> None:
    """A record copied over another round's file is not that round's result: the round is
    computed again, and the tables are those of a clean run."""
    file = _write(tmp_path / "in" / "m.json", make_match())
    out = tmp_path / "out"
    args = ("evaluate", str(file.parent), "--no-combat", "--no-figures", "--out", str(out))
    assert _invoke(*args).exit_code == 1
    expected = _rows(out / "players.csv")
    records = sorted((out / "cache" / "rounds").glob("*.msgpack"))
    assert len(records) == 2  # rounds 1 and 2; round 3 has no frames
    shutil.copyfile(records[0], records[1])
    result = _invoke(*args)
    _clean_end(result)
    assert "1 computed" in result.stdout and "1 from the cache" in result.stdout
    assert _rows(out / "players.csv") == expected


# ---- implausible data: fail by default, or replay with warnings --------------------------------


def test_evaluate_replays_implausible_rounds_with_warnings_when_asked(tmp_path: Path) -> None:
    document = make_match()
    frame = document["gameRounds"][0]["frames"][0]  # the first: its HP does not rise after
    next(p for p in frame["ct"]["players"] if p["name"] == "ct1")["hp"] = 250
    file = _write(tmp_path / "in" / "m.json", document)
    warning = "frame 0 (tick 1000): ct1 has HP 250 (at most 100)"

    failing = tmp_path / "fail"
    result = _invoke(
        "evaluate", str(file.parent), "--no-combat", "--no-figures", "--out", str(failing)
    )
    assert result.exit_code == 1
    failures = _rows(failing / "failures.csv")
    assert [(row["round"], row["kind"]) for row in failures] == [
        ("1", "broken round"),
        ("3", "replay error"),
    ]
    assert warning in failures[0]["message"]

    warned = tmp_path / "warn"
    result = _invoke(
        "evaluate",
        str(file.parent),
        "--no-combat",
        "--no-figures",
        "--implausible",
        "warn",
        "--out",
        str(warned),
    )
    assert result.exit_code == 1  # round 3 (no frames) still fails
    assert "1 rounds replayed with implausible data" in result.stdout
    rounds = {row["round"]: row["warnings"] for row in _rows(warned / "rounds.csv")}
    assert rounds == {"1": warning, "2": ""}
    summary: dict[str, Any] = json.loads((warned / "summary.json").read_text())
    assert summary["options"]["implausible"] == "warn"
    assert summary["counts"]["rounds_with_warnings"] == 1
    report = (warned / "report.md").read_text()
    assert "## Implausible data replayed anyway" in report and warning in report
    assert "--implausible warn" in summary["command"]


# ---- property: any mutation of a valid file ends cleanly ----------------------------------------


@pytest.fixture(scope="module")
def fuzz_dir(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return tmp_path_factory.mktemp("cli-fuzz")


FUZZ_EXAMPLES = int(os.environ.get("DECOY_FUZZ_EXAMPLES", "40"))
"""Mutated files per run (CI's default; set DECOY_FUZZ_EXAMPLES for a longer search)."""


@settings(max_examples=FUZZ_EXAMPLES, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(changes=mutations, damage=byte_damage, xz_fraction=compression)
def test_any_mutated_file_ends_in_results_or_one_error_line(
    fuzz_dir: Path,
    changes: list[tuple[tuple[Any, ...], Any]],
    damage: tuple[str, float, int] | None,
    xz_fraction: float | None,
) -> None:
    """`info` and `replay` on a mutated match: exit 0 with every output written, or one
    `error:` line; never a traceback, never an internal error."""
    file = fuzz_dir / "match.json.xz"
    file.write_bytes(damaged_file(changes, damage, xz_fraction))
    _clean_end(_invoke("info", str(file)))
    out = fuzz_dir / "replay"
    shutil.rmtree(out, ignore_errors=True)
    for round_num in (1, 2):
        result = _invoke("replay", f"{file}:{round_num}", "--models", "none", "--out", str(out))
        _clean_end(result)
        if result.exit_code == 0:
            written = {path.name for path in out.iterdir()}
            assert {"replay.csv", "players.csv", "summary.json", "paths.png"} <= written


# ---- the data never chooses where files go -----------------------------------------------------


def test_hostile_ids_and_names_write_only_into_the_output_folders(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """A matchID and player names that look like paths: replay, snap and evaluate write only
    into their output folders."""
    work = tmp_path / "work"
    work.mkdir()
    monkeypatch.chdir(work)
    document = make_match()
    document["matchID"] = "../../../escaped"
    for game_round in document["gameRounds"]:
        for frame in game_round.get("frames") or []:
            for player in frame["t"]["players"]:
                if player["name"] == "t1":
                    player["name"] = "../../escaped/t1"
    file = _write(tmp_path / "in" / "m.json", document)
    before = set(tmp_path.rglob("*"))
    for args in (
        ["replay", f"{file}:1", "--models", "none"],
        ["replay", f"{file}:2", "--models", "none", "--gif", "--out", "r2"],
        ["snap", str(file), "--metrics"],
        ["evaluate", str(file), "--no-combat", "--out", "ev"],
    ):
        _clean_end(_invoke(*args))
    created = set(tmp_path.rglob("*")) - before
    allowed = (work / "decoy-out", work / "r2", work / "ev")
    outside = [p for p in created if not any(p == a or a in p.parents for a in allowed)]
    assert created and not outside, outside
