"""`decoy compare RUN_A RUN_B` on a small hand-made pair of runs (issue 15): the numbers by hand,
and every way two runs can fail to pair is one `error:` line."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from scipy.stats import wilcoxon
from typer.testing import CliRunner

from decoy_cli.cli import app
from decoy_cli.metrics import FASTDTW_METRIC, METRIC_NAMES

runner = CliRunner()
ROUNDS = 12
PLAYERS = ("p1", "p2")


def write_run(folder: Path, change: dict[tuple[int, str], float] | None = None) -> Path:
    """A run folder with players.csv, rounds.csv and tables/places.csv: every metric 1.0 + the
    round/100, plus `change` on mean_dist of the given (round, player)."""
    rows = []
    for r in range(1, ROUNDS + 1):
        for p in PLAYERS:
            row = {"match": "m", "round": r, "player": p, "side": "T", "reason": None}
            row |= {m: 1.0 + r / 100 for m in METRIC_NAMES}
            row["mean_dist"] += (change or {}).get((r, p), 0.0)
            rows.append(row)
    (folder / "tables").mkdir(parents=True)
    pd.DataFrame(rows).to_csv(folder / "players.csv", index=False)
    rounds = pd.DataFrame({"match": "m", "round": range(1, ROUNDS + 1), "file_sha": "abc"})
    rounds.to_csv(folder / "rounds.csv", index=False)
    error = 1.0 + sum((change or {}).values()) / 10
    places = pd.DataFrame({"place": ["LongA", "Mid"], "mean_error_m": [1.0, error]})
    places.to_csv(folder / "tables" / "places.csv", index=False)
    return folder


def better_b() -> dict[tuple[int, str], float]:
    """B is 0.1 m closer on mean_dist in 22 player-rounds, 0.05 m farther in 2."""
    change = {(r, p): -0.1 for r in range(1, ROUNDS + 1) for p in PLAYERS}
    change[(3, "p1")] = change[(7, "p2")] = 0.05
    return change


def test_compare_pairs_two_runs_and_gets_the_numbers_right(tmp_path: Path) -> None:
    a = write_run(tmp_path / "a")
    b = write_run(tmp_path / "b", better_b())
    out = tmp_path / "cmp"
    result = runner.invoke(app, ["compare", str(a), str(b), "--out", str(out)])
    assert result.exit_code == 0, result.output
    assert "24 player-rounds of 12 rounds paired" in result.stdout
    table = pd.read_csv(out / "compare.csv").set_index("metric")
    row = table.loc["mean_dist"]
    assert row["pairs"] == 24
    assert row["mean_difference"] == pytest.approx((22 * -0.1 + 2 * 0.05) / 24)
    assert row["improved_share"] == pytest.approx(22 / 24)
    assert row["worse_share"] == pytest.approx(2 / 24)
    d = np.array([-0.1] * 22 + [0.05] * 2)
    assert row["wilcoxon_p"] == pytest.approx(wilcoxon(d).pvalue)
    assert row["low"] <= row["mean_difference"] <= row["high"] < 0
    same = table.loc["rmse"]  # unchanged: no test, no improvement
    assert same["mean_difference"] == 0 and np.isnan(same["wilcoxon_p"])
    assert "every difference is zero" in same["note"]
    places = pd.read_csv(out / "places.csv")
    assert places.iloc[0]["place"] == "Mid"
    assert places.iloc[0]["difference_m"] == pytest.approx(sum(better_b().values()) / 10)
    text = (out / "compare.md").read_text()
    assert "| `mean_dist` |" in text and "differences.png" in text
    assert (out / "differences.png").stat().st_size > 0
    assert len(pd.read_csv(out / "differences.csv")) == 24


def one_error(result) -> str:
    assert result.exit_code == 1, result.output
    assert "Traceback" not in result.output
    assert result.stderr.count("\n") == 1 and result.stderr.startswith("error: ")
    return result.stderr


def test_runs_that_cannot_be_paired_are_one_error_line(tmp_path: Path) -> None:
    a = write_run(tmp_path / "a")
    out = ["--out", str(tmp_path / "cmp")]
    other = write_run(tmp_path / "other")
    rounds = pd.read_csv(other / "rounds.csv")
    rounds.loc[4, "file_sha"] = "def"
    rounds.to_csv(other / "rounds.csv", index=False)
    assert "different data" in one_error(runner.invoke(app, ["compare", str(a), str(other), *out]))

    empty = tmp_path / "empty"
    empty.mkdir()
    assert "players.csv: not found" in one_error(
        runner.invoke(app, ["compare", str(a), str(empty), *out])
    )
    cut = write_run(tmp_path / "cut")
    text = (cut / "players.csv").read_text()
    (cut / "players.csv").write_text(text[: len(text) - 40])
    assert "truncated" in one_error(runner.invoke(app, ["compare", str(a), str(cut), *out]))

    fewer = write_run(tmp_path / "fewer")
    pd.read_csv(fewer / "players.csv").drop(columns=["paper_dtw"]).to_csv(
        fewer / "players.csv", index=False
    )
    assert "different metric sets" in one_error(
        runner.invoke(app, ["compare", str(a), str(fewer), *out])
    )
    (tmp_path / "binary").mkdir()
    (tmp_path / "binary" / "players.csv").write_bytes(b"\xff\xfe\x00garbage")
    (tmp_path / "binary" / "rounds.csv").write_text("match,round,file_sha\n")
    assert "error: " in one_error(
        runner.invoke(app, ["compare", str(a), str(tmp_path / "binary"), *out])
    )
    assert not (tmp_path / "cmp").exists()


def test_a_run_with_fastdtw_pairs_with_one_without_on_the_shared_metrics(tmp_path: Path) -> None:
    a = write_run(tmp_path / "a")
    b = write_run(tmp_path / "b", better_b())
    players = pd.read_csv(b / "players.csv")
    players[FASTDTW_METRIC] = 0.5
    players.to_csv(b / "players.csv", index=False)
    out = tmp_path / "cmp"
    result = runner.invoke(app, ["compare", str(a), str(b), "--out", str(out)])
    assert result.exit_code == 0, result.output
    assert f"only one run has {FASTDTW_METRIC}: left out" in result.stdout
    table = pd.read_csv(out / "compare.csv")
    assert list(table["metric"]) == list(METRIC_NAMES)
    assert f"Only one run computed {FASTDTW_METRIC}: left out." in (out / "compare.md").read_text()
