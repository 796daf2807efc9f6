"""Numbers at the edge of a float in the tables `decoy compare` reads (issue 51): a metric near
the float limit (or infinite, or negative) is refused by name, one `error:` line naming the
file, column and row; large values a replay could give are compared without overflow; no
output holds `inf`."""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from run_fixtures import write_run
from typer.testing import CliRunner

from decoy_cli.cli import app
from decoy_cli.evaluate.run_tables import MAX_METRIC_M

runner = CliRunner()


def compare(a: Path, b: Path, out: Path):
    return runner.invoke(app, ["compare", str(a), str(b), "--out", str(out)])


@pytest.mark.parametrize("value", [sys.float_info.max, 1.7e308, float("inf"), -1.0])
def test_a_metric_beyond_any_distance_is_refused_by_name(tmp_path: Path, value: float) -> None:
    a = write_run(tmp_path / "a", value)
    b = write_run(tmp_path / "b", 1.0)
    for first, second in ((a, b), (b, a)):
        result = compare(first, second, tmp_path / "cmp")
        assert result.exit_code == 1, result.output
        assert result.stderr.count("\n") == 1, result.stderr
        assert result.stderr.startswith(f"error: {a / 'players.csv'}: column mean_dist, data row 1")
        assert "is not a distance in [0, 1e+09] m" in result.stderr
    assert not (tmp_path / "cmp").exists()


def test_near_the_float_limit_in_both_runs_is_not_inf(tmp_path: Path) -> None:
    a = write_run(tmp_path / "a", 1.7e308)
    b = write_run(tmp_path / "b", 1.6e308)
    result = compare(a, b, tmp_path / "cmp")
    assert result.exit_code == 1 and "is not a distance" in result.stderr, result.output
    assert "inf" not in result.output


def test_the_largest_metric_a_replay_may_have_compares_exactly(tmp_path: Path) -> None:
    a = write_run(tmp_path / "a", MAX_METRIC_M)
    b = write_run(tmp_path / "b", 0.0)
    result = compare(a, b, tmp_path / "cmp")
    assert result.exit_code == 0, result.output
    table = pd.read_csv(tmp_path / "cmp" / "compare.csv").set_index("metric")
    numbers = table.drop(columns=["note"]).to_numpy(np.float64)
    assert not np.isinf(numbers).any()
    assert table.loc["mean_dist", "mean_difference"] == -MAX_METRIC_M
    assert table.loc["mean_dist", "mean_a"] == MAX_METRIC_M
