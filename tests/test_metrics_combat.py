"""HP, death-time and outcome metrics on hand-computed cases and degenerate input."""

from __future__ import annotations

import math

import numpy as np
import pytest

from decoy_cli.metrics import (
    DEATH_COUNT_NAMES,
    HP_METRIC_NAMES,
    death_time_metrics,
    hp_metrics,
    outcome_metrics,
    pearson,
)


def test_pearson_hand_case_and_degenerate_series() -> None:
    # x = 1, 2, 3 and y = 1, 3, 2: centred -1, 0, 1 and -1, 1, 0; sum of products 1, sums of
    #   squares 2 and 2: r = 1 / 2.
    assert pearson(np.array([1.0, 2.0, 3.0]), np.array([1.0, 3.0, 2.0])) == (0.5, None)
    assert pearson(np.array([1.0, 2.0]), np.array([5.0, 3.0]))[0] == pytest.approx(-1.0)
    r, reason = pearson(np.array([0.1, 0.1, 0.1]), np.array([1.0, 2.0, 3.0]))
    assert math.isnan(r) and reason == "original series is constant"
    r, reason = pearson(np.array([1.0, 2.0, 3.0]), np.array([7.0, 7.0, 7.0]))
    assert math.isnan(r) and reason == "simulated series is constant"
    r, reason = pearson(np.array([1.0]), np.array([2.0]))
    assert math.isnan(r) and reason == "fewer than 2 values"


def test_hp_metrics_hand_case() -> None:
    # Two players over frames 0, 1, 2:
    #   A original 100 100 40, simulated 100 80 40; B original 100 60 0, simulated 100 100 0.
    # Pooled: x = 100 100 40 100 60 0 (mean 200/3), y = 100 80 40 100 100 0 (mean 70);
    #   centred x = (100 100 -80 100 -20 -200)/3, y = 30 10 -30 30 30 -70;
    #   Σxy = 22800/3 = 7600, Σx² = 76800/9, Σy² = 8600.
    # Mean curves: original 100 80 20, simulated 100 90 20; centred (100 40 -140)/3 and
    #   30 20 -50: Σxy = 3600, Σx² = 31200/9, Σy² = 3800.
    # RMSE: differences 0 20 0 0 -40 0 -> sqrt(2000 / 6).
    result = hp_metrics([100, 100, 40, 100, 60, 0], [100, 80, 40, 100, 100, 0], [0, 1, 2, 0, 1, 2])
    assert list(result.values) == list(HP_METRIC_NAMES)
    assert result.reasons == {}
    assert result.n_player_frames == 6 and result.n_frame_times == 3
    assert result.values["hp_corr"] == pytest.approx(7600 / math.sqrt(76800 / 9 * 8600), rel=1e-12)
    assert result.values["paper_hp_corr"] == pytest.approx(
        3600 / math.sqrt(31200 / 9 * 3800), rel=1e-12
    )
    assert result.values["hp_rmse"] == pytest.approx(math.sqrt(2000 / 6), rel=1e-12)


def test_hp_metrics_degenerate() -> None:
    constant = hp_metrics([100, 100, 100], [100, 50, 0], [0, 1, 2])
    assert math.isnan(constant.values["hp_corr"])
    assert constant.reasons["hp_corr"] == "original series is constant"
    assert constant.reasons["paper_hp_corr"] == "original series is constant"
    assert constant.values["hp_rmse"] == pytest.approx(math.sqrt((0 + 2500 + 10000) / 3))
    assert "hp_rmse" not in constant.reasons

    empty = hp_metrics([], [], [])
    assert all(math.isnan(v) for v in empty.values.values())
    assert empty.reasons["hp_rmse"] == "no player-frames"
    assert empty.reasons["hp_corr"] == "fewer than 2 values"

    with pytest.raises(ValueError, match="same length"):
        hp_metrics([1, 2], [1, 2, 3], [0, 1])
    with pytest.raises(ValueError, match="finite"):
        hp_metrics([1, np.nan], [1, 2], [0, 1])
    with pytest.raises(ValueError, match="integer"):
        hp_metrics([1, 2], [1, 2], [0.0, 0.5])


def test_death_time_metrics_hand_case() -> None:
    # Players 0, 4, 5 died in both: (10, 12), (20, 26), (40, 40) -> MAE (2 + 6 + 0) / 3.
    #   Correlation: x centred (-40 -10 50)/3, y = 12 26 40 centred -14 0 14; Σxy = 420,
    #   Σx² = 4200/9, Σy² = 392. Player 2 died only in the original, player 1 only in the
    #   simulation, player 3 in neither.
    result = death_time_metrics([10, None, 30, None, 20, 40], [12, 15, np.nan, None, 26, 40])
    assert result.values["death_time_mae_s"] == pytest.approx(8 / 3, rel=1e-12)
    assert result.values["death_time_corr"] == pytest.approx(
        420 / math.sqrt(4200 / 9 * 392), rel=1e-12
    )
    assert result.reasons == {}
    assert tuple(result.counts) == DEATH_COUNT_NAMES
    assert result.counts == {
        "died_both": 3,
        "died_only_original": 1,
        "died_only_simulated": 1,
        "died_neither": 1,
    }


def test_death_time_metrics_degenerate() -> None:
    one = death_time_metrics([5.0, np.nan], [8.0, 3.0])
    assert one.values["death_time_mae_s"] == 3.0
    assert math.isnan(one.values["death_time_corr"])
    assert one.reasons == {"death_time_corr": "fewer than 2 values"}

    none = death_time_metrics([np.nan, 4.0], [2.0, np.nan])
    assert all(math.isnan(v) for v in none.values.values())
    assert set(none.reasons.values()) == {"no player died in both"}
    assert none.counts["died_both"] == 0

    empty = death_time_metrics([], [])
    assert empty.counts == dict.fromkeys(DEATH_COUNT_NAMES, 0)

    with pytest.raises(ValueError, match="non-negative"):
        death_time_metrics([-1.0], [2.0])
    with pytest.raises(ValueError, match="non-negative"):
        death_time_metrics([1.0], [np.inf])
    with pytest.raises(ValueError, match="same length"):
        death_time_metrics([1.0], [1.0, 2.0])


def test_outcome_metrics_hand_case() -> None:
    result = outcome_metrics(
        ["T", "CT", "T", "CT"],
        ["T", "T", "T", "CT"],
        ["elimination", "bomb", "time", "elimination"],
        ["elimination", "elimination", "time", "defuse"],
    )
    assert result.n_rounds == 4
    assert result.values == {"outcome_agreement": 0.75, "end_reason_agreement": 0.5}
    assert result.reasons == {}
    winners = result.winner_confusion
    assert list(winners.index) == ["CT", "T"] and list(winners.columns) == ["CT", "T"]
    assert winners.index.name == "original" and winners.columns.name == "simulated"
    assert winners.to_numpy().tolist() == [[1, 1], [0, 2]]
    reasons = result.end_reason_confusion
    assert reasons is not None
    assert list(reasons.index) == ["bomb", "defuse", "elimination", "time"]
    assert reasons.to_numpy().tolist() == [[0, 0, 1, 0], [0, 0, 0, 0], [0, 1, 1, 0], [0, 0, 0, 1]]
    assert int(reasons.to_numpy().sum()) == 4


def test_outcome_metrics_degenerate() -> None:
    no_reasons = outcome_metrics(["T"], ["CT"])
    assert no_reasons.values["outcome_agreement"] == 0.0
    assert math.isnan(no_reasons.values["end_reason_agreement"])
    assert no_reasons.reasons == {"end_reason_agreement": "end reasons not given"}
    assert no_reasons.end_reason_confusion is None

    empty = outcome_metrics([], [], [], [])
    assert empty.n_rounds == 0
    assert empty.reasons == {"outcome_agreement": "no rounds", "end_reason_agreement": "no rounds"}
    assert empty.winner_confusion.empty

    with pytest.raises(ValueError, match="same length"):
        outcome_metrics(["T", "CT"], ["T"])
    with pytest.raises(ValueError, match="both"):
        outcome_metrics(["T"], ["T"], ["time"], None)
    with pytest.raises(ValueError, match="non-empty strings"):
        outcome_metrics(["T"], [None])  # type: ignore[list-item]
