"""Bootstrap intervals by round (decoy_cli/metrics/bootstrap.py)."""

from __future__ import annotations

import numpy as np
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
