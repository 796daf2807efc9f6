"""The frame rate of a round's data: how densely its positions were parsed (awpy's default 2
frames per second in ESTA, 1 to 128 in other exports), for the reports to state."""

from __future__ import annotations

import numpy as np

CHANGE = 0.1
"""Relative difference between the 10th and 90th percentile of a round's frame-to-frame rates
from which its rate counts as changing within the round (a single missing frame does not)."""


def frame_rates(seconds: np.ndarray) -> tuple[float, float, float]:
    """(median, 10th, 90th percentile) of a round's frames per second, one rate per pair of
    consecutive frames at distinct times; NaN for a round with fewer than two."""
    gaps = np.diff(np.asarray(seconds, dtype=np.float64))
    gaps = gaps[gaps > 0]
    if not len(gaps):
        return float("nan"), float("nan"), float("nan")
    rates = 1.0 / gaps
    low, median, high = np.percentile(rates, [10, 50, 90])
    return float(median), float(low), float(high)


def per_second(rate: float) -> str:
    """ "1 frame/s", "8 frames/s", "0.5 frames/s" (three significant digits)."""
    return f"{rate:.3g} frame/s" if f"{rate:.3g}" == "1" else f"{rate:.3g} frames/s"


def describe_frame_rate(seconds: np.ndarray) -> str:
    """ "8 frames/s", or "1 to 8 frames/s (changes within the round)", or "one frame"."""
    median, low, high = frame_rates(seconds)
    if not np.isfinite(median):
        return "one frame" if len(seconds) == 1 else "no frames"
    if high - low > CHANGE * median:
        return f"{low:.3g} to {per_second(high)} (changes within the round)"
    return per_second(median)


def describe_rates(rates: np.ndarray) -> str:
    """Rounds' median frame rates (frames/s, NaN unknown) in a few words: one rate, or their
    range."""
    rates = np.asarray(rates, dtype=np.float64)
    rates = rates[np.isfinite(rates)]
    if not len(rates):
        return "not known"
    low, high = float(rates.min()), float(rates.max())
    if high - low <= CHANGE * high:
        return per_second(float(np.median(rates)))
    return f"{low:.3g} to {per_second(high)} (each round's median, rounds.csv `frame_rate`)"
