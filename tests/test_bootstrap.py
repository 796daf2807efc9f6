"""Bootstrap intervals by round (decoy_cli/metrics/bootstrap.py)."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from decoy_cli.metrics.bootstrap import MIN_ROUNDS, RoundBootstrap


def rows(rounds: int = 40, seed: int = 1) -> tuple[np.ndarray, np.ndarray]:
    rng = np.random.default_rng(seed)
    per_round = rng.integers(1, 6, size=rounds)
    index = np.repeat(np.arange(rounds), per_round)
    values = rng.normal(size=rounds)[index] + 0.1 * rng.normal(size=len(index))
    return values, index


def test_each_resample_is_the_statistic_of_the_drawn_rounds_rows() -> None:
    values, index = rows()
    boot = RoundBootstrap(40, resamples=50, seed=3)
    means, medians = boot._means(values, index), boot._medians(values, index)
    for b in range(50):
        drawn = np.concatenate(
            [values[index == r] for r in np.repeat(np.arange(40), boot.weights[b])]
        )
        assert means[b] == pytest.approx(np.mean(drawn))
        assert medians[b] == pytest.approx(np.median(drawn))


def test_an_interval_covers_the_statistic_and_is_reproducible() -> None:
    values, index = rows()
    first = RoundBootstrap(40, seed=0).interval(values, index, "mean")
    again = RoundBootstrap(40, seed=0).interval(values, index, "mean")
    assert first == again
    assert first.low < values.mean() < first.high
    median = RoundBootstrap(40, seed=0).interval(values, index, "median")
    assert median.low < np.median(values) < median.high


def test_rounds_not_rows_are_resampled() -> None:
    """Rows of a round that move together: the interval is as wide as the rounds' spread says,
    far wider than resampling the rows one by one would make it."""
    values, index = rows()
    by_round = RoundBootstrap(40, seed=0).interval(values, index, "mean")
    n = len(values)
    by_row = RoundBootstrap(n, seed=0).interval(values, np.arange(n), "mean")
    assert by_round.high - by_round.low > 1.3 * (by_row.high - by_row.low)


def test_too_few_rounds_give_no_interval() -> None:
    values, index = rows(rounds=MIN_ROUNDS - 1)
    interval = RoundBootstrap(MIN_ROUNDS - 1).interval(values, index, "mean")
    assert np.isnan(interval.low) and np.isnan(interval.high)
    assert "fewer than" in interval.note
    with pytest.raises(ValueError, match="mean' or 'median"):
        RoundBootstrap(40).interval(*rows(), "p90")


def test_statistics_from_per_round_sums() -> None:
    """A correlation bootstrapped from per-round moments: each resample's value is the Pearson
    correlation of the drawn rounds' pairs."""
    from decoy_cli.metrics.bootstrap import pearson_from_sums

    rng = np.random.default_rng(5)
    index = np.repeat(np.arange(20), 3)
    x = rng.normal(size=60)
    y = x + rng.normal(size=60)
    sums = np.zeros((20, 6))
    for k, column in enumerate((np.ones(60), x, y, x * x, y * y, x * y)):
        np.add.at(sums[:, k], index, column)
    assert pearson_from_sums(sums.sum(axis=0, keepdims=True))[0] == pytest.approx(
        np.corrcoef(x, y)[0, 1]
    )
    boot = RoundBootstrap(20, resamples=30, seed=2)
    draws = pearson_from_sums(boot.weights @ sums)
    for b in range(30):
        keep = np.repeat(np.arange(20), boot.weights[b])
        rows = np.concatenate([np.flatnonzero(index == r) for r in keep])
        assert draws[b] == pytest.approx(np.corrcoef(x[rows], y[rows])[0, 1])
    interval = boot.sums_interval(sums, pearson_from_sums)
    assert interval.low <= np.corrcoef(x, y)[0, 1] <= interval.high


def test_the_combat_table_gets_intervals_by_round() -> None:
    from decoy_cli.evaluate.intervals import combat_intervals

    rounds = pd.DataFrame(
        {
            "match": ["m"] * 12,
            "round": range(1, 13),
            "winner_original": ["T", "CT"] * 6,
            "winner_replay": ["T", "CT", "CT", "CT"] * 3,
            "reason_original": [None] * 12,
            "reason_replay": [None] * 12,
            "played_out_s": [0.0] * 12,
        }
    )
    players = pd.DataFrame(
        {
            "match": ["m"] * 12,
            "round": range(1, 13),
            "death_time_original_s": np.linspace(10, 60, 12),
            "death_time_replay_s": np.linspace(12, 70, 12),
        }
    )
    hp = np.tile([10, 800, 790, 70000, 69000, 69500, 40], (12, 1)).astype(float)
    combat = pd.DataFrame(
        {
            "metric": ["outcome_agreement", "death_time_mae_s", "hp_rmse", "paper_hp_corr"],
            "value": [0.75, 6.0, 2.0, 0.9],
        }
    )
    table = combat_intervals(combat, players, rounds, hp, seed=0).set_index("metric")
    low, high = table.loc["outcome_agreement", ["low", "high"]]
    assert low < 0.75 < high
    assert table.loc["hp_rmse", "low"] == pytest.approx(2.0)  # every round alike
    assert np.isnan(table.loc["paper_hp_corr", "low"])
    assert "mean curves" in table.loc["paper_hp_corr", "interval_note"]
