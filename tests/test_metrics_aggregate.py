"""Aggregation by side and overall on hand-made metric frames."""

from __future__ import annotations

import math

import numpy as np
import pandas as pd
import pytest

from decoy_cli.metrics import GROUPS, PlayerRound, summarize, trajectory_metrics_frame

METRICS = ("mean_dist", "dtw")
NAN = float("nan")
SHORT = "simulated alive in fewer than 2 frames"
DISJOINT = "no frame alive in both"


def hand_frame() -> pd.DataFrame:
    rows = [
        ("T", 1.0, 0.5, None),
        ("T", 2.0, 0.5, None),
        ("T", 3.0, 0.5, None),
        ("T", 4.0, 0.5, None),
        ("T", NAN, NAN, SHORT),
        ("CT", 10.0, 1.0, None),
        ("CT", 20.0, 3.0, None),
        ("CT", NAN, NAN, SHORT),
        ("CT", NAN, NAN, DISJOINT),
    ]
    return pd.DataFrame(rows, columns=["side", *METRICS, "reason"])


def stat(table: pd.DataFrame, group: str, metric: str) -> pd.Series:
    row = table[(table["group"] == group) & (table["metric"] == metric)]
    assert len(row) == 1
    return row.iloc[0]


def test_statistics_by_side_and_overall() -> None:
    summary = summarize(hand_frame(), METRICS)
    table = summary.table
    assert list(table.columns) == ["group", "metric", "n", "mean", "std", "median", "p90"]
    assert list(table["group"]) == [g for g in GROUPS for _ in METRICS]

    # T mean_dist 1, 2, 3, 4: mean 2.5, sample std sqrt((2.25 + 0.25 + 0.25 + 2.25) / 3),
    #   median 2.5, p90 at rank 0.9 * 3 = 2.7 -> 3 + 0.7 * (4 - 3) = 3.7.
    t = stat(table, "T", "mean_dist")
    assert t["n"] == 4
    assert t["mean"] == 2.5
    assert t["std"] == pytest.approx(math.sqrt(5 / 3), rel=1e-12)
    assert t["median"] == 2.5
    assert t["p90"] == pytest.approx(3.7, rel=1e-12)
    # CT mean_dist 10, 20: mean 15, sample std sqrt(50), p90 at rank 0.9 -> 19.
    ct = stat(table, "CT", "mean_dist")
    assert (ct["n"], ct["mean"], ct["median"]) == (2, 15.0, 15.0)
    assert ct["std"] == pytest.approx(math.sqrt(50), rel=1e-12)
    assert ct["p90"] == pytest.approx(19.0, rel=1e-12)
    # All: 1, 2, 3, 4, 10, 20: mean 40/6, median 3.5, p90 at rank 4.5 -> 10 + 0.5 * 10 = 15;
    #   squared deviations from 20/3 sum to Σx² - n·mean² = 530 - 800/3 = 790/3 (5 dof).
    overall = stat(table, "all", "mean_dist")
    assert overall["n"] == 6
    assert overall["mean"] == pytest.approx(20 / 3, rel=1e-12)
    assert overall["median"] == 3.5
    assert overall["p90"] == pytest.approx(15.0, rel=1e-12)
    assert overall["std"] == pytest.approx(math.sqrt(790 / 3 / 5), rel=1e-12)
    # T dtw is constant: std 0.
    assert stat(table, "T", "dtw")["std"] == 0.0

    assert summary.n_rows == {"T": 5, "CT": 4, "all": 9}
    assert summary.n_evaluated == {"T": 4, "CT": 2, "all": 6}


def test_unevaluated_rows_are_counted_by_reason() -> None:
    unevaluated = summarize(hand_frame(), METRICS).unevaluated
    assert list(unevaluated.columns) == ["group", "reason", "count"]
    assert unevaluated.to_records(index=False).tolist() == [
        ("T", SHORT, 1),
        ("CT", DISJOINT, 1),
        ("CT", SHORT, 1),
        ("all", SHORT, 2),
        ("all", DISJOINT, 1),
    ]


def test_small_and_empty_groups() -> None:
    frame = pd.DataFrame(
        [("T", 2.0, 1.0, None), ("CT", NAN, NAN, SHORT)], columns=["side", *METRICS, "reason"]
    )
    table = summarize(frame, METRICS).table
    single = stat(table, "T", "mean_dist")
    assert single["n"] == 1 and single["mean"] == 2.0 and math.isnan(single["std"])
    assert single["p90"] == 2.0
    empty = stat(table, "CT", "dtw")
    assert empty["n"] == 0
    assert all(math.isnan(empty[c]) for c in ("mean", "std", "median", "p90"))

    nothing = summarize(pd.DataFrame(columns=["side", *METRICS, "reason"]), METRICS)
    assert (nothing.table["n"] == 0).all() and nothing.table["mean"].isna().all()
    assert nothing.unevaluated.empty
    assert nothing.n_rows == dict.fromkeys(GROUPS, 0)


def test_bad_frames_raise() -> None:
    frame = hand_frame()
    broken = frame.copy()
    broken.loc[0, "dtw"] = np.nan
    with pytest.raises(ValueError, match=r"1 evaluated rows .* \['dtw'\]"):
        summarize(broken, METRICS)
    sides = frame.copy()
    sides.loc[0, "side"] = "spectator"
    with pytest.raises(ValueError, match="side must be one of"):
        summarize(sides, METRICS)
    with pytest.raises(ValueError, match=r"lacks columns: \['reason'\]"):
        summarize(frame.drop(columns="reason"), METRICS)


def test_summarize_the_output_of_trajectory_metrics_frame() -> None:
    line = np.c_[np.arange(8.0), np.zeros(8), np.zeros(8)]
    alive = np.ones(8, dtype=bool)
    dead = np.zeros(8, dtype=bool)
    rounds = [
        PlayerRound({"side": "T"}, line, alive, line + 1.0, alive),
        PlayerRound({"side": "CT"}, line, alive, line + 2.0, alive),
        PlayerRound({"side": "CT"}, line, alive, line, dead),
    ]
    summary = summarize(trajectory_metrics_frame(rounds))
    overall = stat(summary.table, "all", "mean_dist")
    # Offsets (1, 1, 1) and (2, 2, 2): distances sqrt(3) and 2 sqrt(3).
    assert overall["n"] == 2
    assert overall["mean"] == pytest.approx(1.5 * math.sqrt(3), rel=1e-12)
    assert summary.unevaluated.to_records(index=False).tolist() == [
        ("CT", SHORT, 1),
        ("all", SHORT, 1),
    ]
