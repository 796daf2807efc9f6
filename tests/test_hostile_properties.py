"""Property-based tests of the loaders of issue 51: each field of each file kind given a hostile
value (hypothesis: any JSON value, NaN and infinities, numbers beyond a float or 64 bits, deep
nesting, text of any kind; any CSV cell), and each loader either returns what its callers may
rely on or raises its one-line error (a DecoyError): never another exception."""

from __future__ import annotations

import json
import math
import shutil
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd
import pytest
from esta_fixtures import make_match, write_match
from hostile_values import hostile_cell, hostile_json, leaf_places, put
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from typer.testing import CliRunner

from decoy_cli.cli import app
from decoy_cli.damage.calibration import CALIBRATION_FILE
from decoy_cli.damage.model_folder import load_calibration, load_dip
from decoy_cli.damage.rules_damage import RULES_FILE, RulesFile
from decoy_cli.errors import DecoyError, ModelError
from decoy_cli.evaluate.cache import RunCache
from decoy_cli.evaluate.run_tables import (
    DISTANCE_COLUMNS,
    FLAG_COLUMNS,
    MAX_METRIC_M,
    NUMBER_COLUMNS,
    read_run_table,
)
from decoy_cli.reading import MAX_JSON_DEPTH, MAX_JSON_INT, parse_json

ROOT = Path(__file__).resolve().parents[1]
MODELS = ROOT / "models"
SOME = settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow])


def _places(name: str) -> list[tuple[str | int, ...]]:
    return leaf_places(json.loads((MODELS / name).read_text()))


@pytest.fixture(scope="module")
def folder(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A model folder (the shipped DIP, calibration and rules) the tests write into."""
    folder = tmp_path_factory.mktemp("models")
    for name in ("dip.pt", "dip.json", CALIBRATION_FILE, RULES_FILE):
        shutil.copy(MODELS / name, folder / name)
    return folder


def _depth(value: Any) -> int:
    if isinstance(value, dict | list):
        children = value.values() if isinstance(value, dict) else value
        return 1 + max((_depth(v) for v in children), default=0)
    return 0


def _numbers(value: Any) -> list[int | float]:
    if isinstance(value, dict | list):
        children = value.values() if isinstance(value, dict) else value
        return [n for v in children for n in _numbers(v)]
    return [value] if isinstance(value, int | float) and not isinstance(value, bool) else []


@SOME
@given(st.one_of(hostile_json(), st.binary(max_size=200).map(lambda b: b.decode("latin-1"))))
def test_the_json_loader_returns_checked_json_or_one_error(text: str) -> None:
    for data in (text, text.encode("utf-8", "surrogatepass")):
        try:
            document = parse_json(data, "x.json", ModelError)
        except ModelError as error:
            assert str(error).startswith("x.json: ") and "\n" not in str(error)
            continue
        assert _depth(document) <= MAX_JSON_DEPTH
        for number in _numbers(document):
            assert math.isfinite(number)
            assert isinstance(number, float) or abs(number) < MAX_JSON_INT


@SOME
@given(place=st.sampled_from(_places("dip.json")), raw=hostile_json())
def test_dip_json_loads_or_is_one_model_error(folder: Path, place: Any, raw: str) -> None:
    (folder / "dip.json").write_text(put(json.loads((MODELS / "dip.json").read_text()), place, raw))
    try:
        dip = load_dip(folder)
    except ModelError:
        return
    assert 0.0 <= dip.threshold <= 1.0 and isinstance(dip.metadata, dict)


@SOME
@given(place=st.sampled_from(_places(CALIBRATION_FILE)), raw=hostile_json())
def test_a_calibration_loads_or_is_one_model_error(folder: Path, place: Any, raw: str) -> None:
    document = json.loads((MODELS / CALIBRATION_FILE).read_text())
    (folder / CALIBRATION_FILE).write_text(put(document, place, raw))
    try:
        calibration = load_calibration(folder)
    except ModelError:
        return
    assert calibration is not None
    assert all(math.isfinite(v) for v in (calibration.a, calibration.b, calibration.threshold))
    assert 0.0 <= calibration.threshold <= 1.0


@SOME
@given(place=st.sampled_from(_places(RULES_FILE)), raw=hostile_json())
def test_rules_json_loads_or_is_one_model_error(folder: Path, place: Any, raw: str) -> None:
    (folder / RULES_FILE).write_text(put(json.loads((MODELS / RULES_FILE).read_text()), place, raw))
    try:
        rules = RulesFile.load(folder)
    except ModelError:
        return
    for counts in (rules.bullets, rules.bullets_hurt):
        for table in (counts.counts, counts.killed) if counts is not None else ():
            values = [v for row in table.values() for v in row]
            assert all(math.isfinite(v) and v >= 0 for v in values)
    assert all(0.0 <= s <= 1.0 for s in rules.penetration.shares)
    assert len(rules.penetration.shares) <= rules.penetration.hits


@pytest.fixture(scope="module")
def run(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A `decoy evaluate` run of the fixture match, its tables to edit."""
    folder = tmp_path_factory.mktemp("run")
    (folder / "in").mkdir()
    write_match(folder / "in" / "m.json", make_match())
    out = folder / "evaluate"
    args = ["evaluate", str(folder / "in"), "--no-combat", "--no-view", "--no-figures"]
    args += ["--out", str(out)]
    CliRunner().invoke(app, args)
    assert (out / "rounds.csv").is_file()
    return out


TABLES = ("rounds.csv", "players.csv", "tables/places.csv")


@SOME
@given(data=st.data(), cell=hostile_cell())
def test_a_run_table_reads_checked_or_is_one_error(run: Path, data: Any, cell: str) -> None:
    name = data.draw(st.sampled_from(TABLES))
    original = pd.read_csv(run / name, dtype=str, keep_default_na=False)
    column = data.draw(st.sampled_from(list(original.columns)))
    row = data.draw(st.integers(0, len(original) - 1))
    edited = original.copy()
    edited.loc[row, column] = cell
    path = run.parent / "edited" / name
    path.parent.mkdir(parents=True, exist_ok=True)
    edited.to_csv(path, index=False)
    try:
        table = read_run_table(path)
    except DecoyError as error:
        assert str(error).startswith(f"{path}: ") and "\n" not in str(error)
        return
    kind = Path(name).name
    for number in NUMBER_COLUMNS[kind]:
        if number in table.columns:
            assert pd.api.types.is_numeric_dtype(table[number]), number
            if number in DISTANCE_COLUMNS:
                values = table[number].to_numpy(np.float64)
                assert np.all(np.isnan(values) | ((values >= 0) & (values <= MAX_METRIC_M)))
    if "round" in table.columns:
        assert table["round"].dtype == np.int64
    for flag in FLAG_COLUMNS.get(kind, ()):
        assert set(table[flag].dropna().tolist()) <= {True, False}


@SOME
@given(st.binary(max_size=400))
def test_a_damaged_cache_record_counts_as_missing(tmp_path_factory, stored: bytes) -> None:
    cache = RunCache(tmp_path_factory.mktemp("cache"))
    key = "0" * 64
    cache.rounds.mkdir(parents=True)
    cache.round_path(key).write_bytes(stored)
    assert cache.load_round(key) is None


@settings(max_examples=30, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(data=st.data(), raw=hostile_json())
def test_view_of_a_run_with_a_hostile_summary_is_a_page_or_one_error(
    run: Path, data: Any, raw: str
) -> None:
    summary = json.loads((run / "summary.json").read_text())
    place = data.draw(st.sampled_from(leaf_places(summary)))
    copy = run.parent / "hostile-summary"
    shutil.rmtree(copy, ignore_errors=True)
    shutil.copytree(run, copy)
    (copy / "summary.json").write_text(put(summary, place, raw))
    result = CliRunner().invoke(app, ["view", str(copy)])
    assert result.exit_code in (0, 1), result.output
    if result.exit_code == 1:
        assert result.stderr.count("\n") == 1 and result.stderr.startswith("error: ")
