"""Bootstrap confidence intervals that resample whole rounds.

The player-rounds of one round are not independent (the same fight, the same clock, the same
plan errors), so an interval that resampled player-rounds would be too narrow. `RoundBootstrap`
draws `resamples` samples of the rounds with replacement (a fixed seed: the same run gives the
same intervals) as a (resamples, rounds) matrix of how often each round is drawn, and turns any
per-row values with their round into a percentile interval of the mean or the median: each
resample's statistic is over the rows of the drawn rounds, a round drawn twice counting twice.

Below `MIN_ROUNDS` rounds an interval would mislead; `interval` then returns NaN bounds and the
reason.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

RESAMPLES = 1000
"""Bootstrap resamples per interval: the 2.5% and 97.5% percentiles then rest on 25 draws each."""

CONFIDENCE = 0.95

MIN_ROUNDS = 10
"""Fewest rounds an interval is given for: with fewer, the resamples repeat a handful of rounds
and the percentile interval says more about them than about the population."""


@dataclass(frozen=True)
class Interval:
    """A `CONFIDENCE` interval of a statistic; NaN bounds with the reason when not given."""

    low: float
    high: float
    note: str = ""


class RoundBootstrap:
    """Resamples of `rounds` rounds (see the module docstring)."""

    def __init__(self, rounds: int, *, resamples: int = RESAMPLES, seed: int = 0) -> None:
        self.rounds = rounds
        rng = np.random.default_rng(seed)
        self.weights = (
            rng.multinomial(rounds, np.full(rounds, 1.0 / rounds), size=resamples)
            if rounds
            else np.zeros((resamples, 0), np.int64)
        )

    def interval(self, values: np.ndarray, round_index: np.ndarray, statistic: str) -> Interval:
        """Interval of the "mean" or "median" of `values` (one per row; NaN rows are left out),
        each row belonging to round `round_index` (0 .. rounds-1)."""
        values = np.asarray(values, dtype=np.float64)
        round_index = np.asarray(round_index, dtype=np.int64)
        keep = np.isfinite(values)
        values, round_index = values[keep], round_index[keep]
        present = len(np.unique(round_index))
        if present < MIN_ROUNDS:
            return Interval(np.nan, np.nan, f"{present} rounds: fewer than {MIN_ROUNDS}")
        if statistic == "mean":
            draws = self._means(values, round_index)
        elif statistic == "median":
            draws = self._medians(values, round_index)
        else:
            raise ValueError(f"statistic must be 'mean' or 'median', not {statistic!r}")
        return self._percentiles(draws)

    def sums_interval(
        self, sums: np.ndarray, statistic: Callable[[np.ndarray], np.ndarray]
    ) -> Interval:
        """Interval of a statistic computed from additive per-round sums: `sums` is (rounds, k),
        `statistic` maps a (resamples, k) array of summed rounds to (resamples,) values (NaN
        where undefined), e.g. a Pearson correlation from its moments."""
        if self.rounds < MIN_ROUNDS:
            return Interval(np.nan, np.nan, f"{self.rounds} rounds: fewer than {MIN_ROUNDS}")
        return self._percentiles(statistic(self.weights @ np.asarray(sums, dtype=np.float64)))

    def _percentiles(self, draws: np.ndarray) -> Interval:
        draws = draws[np.isfinite(draws)]
        if not len(draws):
            return Interval(np.nan, np.nan, "undefined in every resample")
        tail = 100 * (1 - CONFIDENCE) / 2
        low, high = np.percentile(draws, [tail, 100 - tail])
        return Interval(float(low), float(high))

    def _means(self, values: np.ndarray, round_index: np.ndarray) -> np.ndarray:
        sums = np.bincount(round_index, weights=values, minlength=self.rounds)
        counts = np.bincount(round_index, minlength=self.rounds).astype(np.float64)
        total = self.weights @ counts
        with np.errstate(invalid="ignore", divide="ignore"):
            return np.where(total > 0, (self.weights @ sums) / total, np.nan)

    def _medians(self, values: np.ndarray, round_index: np.ndarray) -> np.ndarray:
        """The median of each resample's multiset of rows, as numpy's median of it would be
        (the mean of the two middle values when their count is even)."""
        order = np.argsort(values, kind="stable")
        ordered = values[order]
        rows = round_index[order]
        medians = np.full(len(self.weights), np.nan)
        step = max(1, _CHUNK_CELLS // max(1, len(values)))  # bounds the memory of `copies`
        for start in range(0, len(self.weights), step):
            copies = self.weights[start : start + step][:, rows]  # (chunk, rows)
            cumulative = np.cumsum(copies, axis=1)
            total = cumulative[:, -1]
            lower = np.argmax(cumulative >= ((total + 1) // 2)[:, None], axis=1)
            upper = np.argmax(cumulative >= (total // 2 + 1)[:, None], axis=1)
            chunk = (ordered[lower] + ordered[upper]) / 2
            medians[start : start + step] = np.where(total > 0, chunk, np.nan)
        return medians


_CHUNK_CELLS = 4_000_000
"""Resample-by-row cells handled at once by the median (32 MB of int64)."""


def pearson_from_sums(sums: np.ndarray) -> np.ndarray:
    """Pearson correlations from summed moments, one per row of [n, Σx, Σy, Σx², Σy², Σxy]
    (NaN where a series is constant or n < 2)."""
    n, sx, sy, sxx, syy, sxy = (sums[:, k] for k in range(6))
    with np.errstate(invalid="ignore", divide="ignore"):
        r = (n * sxy - sx * sy) / np.sqrt((n * sxx - sx * sx) * (n * syy - sy * sy))
    return np.where(n >= 2, np.clip(r, -1.0, 1.0), np.nan)
