"""Hostile edits of a `decoy evaluate` run's files (issue 51), read by `decoy view` and
`decoy compare`: each is one `error:` line naming the file (and the column or field), never the
bug line (exit 2), and nothing the run's files name is a place on disk to read.

One `decoy evaluate` of a small match serves the module; each test edits a copy of it."""

from __future__ import annotations

import json
import os
import shutil
from pathlib import Path

import msgspec
import pandas as pd
import pytest
from esta_fixtures import make_match, write_match
from typer.testing import CliRunner

from decoy_cli.cli import app
from decoy_cli.evaluate.cache import RunCache
from decoy_cli.reading import MAX_JSON_DEPTH
from decoy_cli.world.navmesh import asset_dir

runner = CliRunner()


def one_error(result) -> str:
    """The `error:` line of a command that failed on bad input (exit 1, no bug line)."""
    assert result.exit_code == 1, result.output
    assert "Traceback" not in result.output and "internal error" not in result.output
    assert result.stderr.count("\n") == 1 and result.stderr.startswith("error: "), result.stderr
    return result.stderr.strip()


@pytest.fixture(scope="module")
def run(tmp_path_factory: pytest.TempPathFactory) -> Path:
    folder = tmp_path_factory.mktemp("run")
    (folder / "in").mkdir()
    write_match(folder / "in" / "m.json", make_match())
    out = folder / "evaluate"
    result = runner.invoke(
        app,
        [
            "evaluate",
            str(folder / "in"),
            "--no-combat",
            "--no-view",
            "--no-figures",
            "--out",
            str(out),
        ],
    )
    # exit 1: the fixture's round without frames is a recorded failure
    assert result.exit_code == 1 and (out / "rounds.csv").is_file(), result.output
    return out


@pytest.fixture
def copy(run: Path, tmp_path: Path) -> Path:
    return Path(shutil.copytree(run, tmp_path / "run"))


def view(folder: Path):
    return runner.invoke(app, ["view", str(folder), "--out", str(folder / "page.html")])


def test_deep_json_in_summary_json_is_one_error_line(copy: Path) -> None:
    summary = copy / "summary.json"
    data = json.loads(summary.read_text())
    summary.write_text(json.dumps(data)[:-1] + ', "deep": ' + "[" * 100_000 + "]" * 100_000 + "}")
    line = one_error(view(copy))
    assert f"{summary}: JSON nested deeper than {MAX_JSON_DEPTH} levels" in line
    assert not (copy / "page.html").exists()


def edit_cell(path: Path, column: str, value: str, row: int = 0) -> None:
    """Write `value` into one cell of the CSV table `path`."""
    frame = pd.read_csv(path, dtype=str, keep_default_na=False)
    frame.loc[row, column] = value
    frame.to_csv(path, index=False)


@pytest.mark.parametrize(
    ("table", "column"),
    [
        ("rounds.csv", "seconds"),
        ("rounds.csv", "round"),
        ("rounds.csv", "frames"),
        ("rounds.csv", "smokes"),
        ("players.csv", "round"),
        ("players.csv", "mean_dist"),
        ("players.csv", "late_share"),
        ("players.csv", "hp_rmse"),
        ("players.csv", "died_original"),
        ("tables/places.csv", "mean_error_m"),
    ],
)
def test_a_text_cell_in_a_number_column_is_one_error_line(
    copy: Path, run: Path, table: str, column: str
) -> None:
    edit_cell(copy / table, column, "abc")
    said = f"{copy / table}: column {column}, data row 1: 'abc' is not"
    if table != "tables/places.csv":  # the page shows the places table as it is
        assert said in one_error(view(copy))
    both = [
        ["compare", str(a), str(b), "--out", str(copy / "cmp")]
        for a, b in ((copy, run), (run, copy))
    ]
    for args in both:
        assert said in one_error(runner.invoke(app, args))


@pytest.mark.parametrize("name", ["elsewhere", "../de_dust2", "de_dust2/../de_dust2"])
def test_a_map_name_that_is_a_path_is_never_read(copy: Path, tmp_path: Path, name: str) -> None:
    elsewhere = tmp_path / "elsewhere"
    shutil.copytree(asset_dir("de_dust2"), elsewhere)  # a whole map's files, to be read or not
    summary = copy / "summary.json"
    data = json.loads(summary.read_text())
    data["options"]["map"] = str(elsewhere) if name == "elsewhere" else name
    summary.write_text(json.dumps(data))
    line = one_error(view(copy))
    assert "no built-in map" in line and "this decoy knows: de_ancient" in line
    assert not (copy / "page.html").exists()


def test_a_cache_key_that_is_a_path_is_never_read(copy: Path, tmp_path: Path) -> None:
    summary = copy / "summary.json"
    data = json.loads(summary.read_text())
    cache = RunCache(copy)
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    for round_id, key in list(data["cache_keys"].items()):
        # the same record, moved out of the cache under a key that walks out of it
        outside = os.path.relpath(elsewhere / key, cache.rounds)
        record = cache.load_round(key)
        assert record is not None
        stored = msgspec.msgpack.encode(msgspec.structs.replace(record, key=outside))
        (elsewhere / f"{key}.msgpack").write_bytes(stored)
        cache.round_path(key).unlink()
        data["cache_keys"][round_id] = outside
    summary.write_text(json.dumps(data))
    assert "the cached result of round" in one_error(view(copy))
    assert not (copy / "page.html").exists()
