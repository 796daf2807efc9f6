"""Aggregate per-player-round metrics: mean, std, median and p90 by side (T, CT) and overall.

The input has one row per player-round with a `side` column ("T" or "CT"), one column per metric
and a `reason` column (None/NaN when the row was evaluated, otherwise why it was not). Rows with a
reason are left out of the statistics but counted and listed by reason, never dropped silently;
an evaluated row with a missing metric value is an error.

Statistics: `std` is the sample standard deviation (ddof = 1; NaN for fewer than 2 rows), `p90`
the 90th percentile with linear interpolation between order statistics (numpy's default).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import pandas as pd

from decoy_cli.metrics.trajectory import METRIC_NAMES

SIDES = ("T", "CT")
OVERALL = "all"
GROUPS = (*SIDES, OVERALL)
"""Groups of the summary, in output order: each side, then all player-rounds."""

STAT_COLUMNS = ("n", "mean", "std", "median", "p90")


@dataclass(frozen=True)
class MetricSummary:
    """Tidy statistics and the accounting of the rows that could not be evaluated."""

    table: pd.DataFrame  # columns: group, metric, n, mean, std, median, p90
    unevaluated: pd.DataFrame  # columns: group, reason, count (non-zero counts only)
    n_rows: dict[str, int]  # group -> player-rounds in the input
    n_evaluated: dict[str, int]  # group -> player-rounds that entered the statistics


def _stats(values: np.ndarray) -> dict[str, float]:
    """n, mean, sample std, median and p90 of a 1-D array (NaN statistics when empty)."""
    n = values.size
    nan = float("nan")
    return {
        "n": n,
        "mean": float(values.mean()) if n else nan,
        "std": float(values.std(ddof=1)) if n > 1 else nan,
        "median": float(np.median(values)) if n else nan,
        "p90": float(np.percentile(values, 90)) if n else nan,
    }


def summarize(frame: pd.DataFrame, metric_names: Sequence[str] = METRIC_NAMES) -> MetricSummary:
    """Statistics per (group, metric) over the evaluated rows, and counts of the others by reason.

    Raises ValueError for missing columns, a side other than T/CT, or an evaluated row whose
    metric value is missing or infinite.
    """
    missing = [c for c in ("side", "reason", *metric_names) if c not in frame.columns]
    if missing:
        raise ValueError(f"metrics frame lacks columns: {missing}")
    bad_sides = sorted(set(frame["side"]) - set(SIDES), key=str)
    if bad_sides:
        raise ValueError(f"side must be one of {SIDES}, got {bad_sides}")

    reason = frame["reason"]
    evaluated = reason.isna()
    values = frame[list(metric_names)].to_numpy(dtype=np.float64)
    broken = evaluated.to_numpy() & ~np.isfinite(values).all(axis=1)
    if broken.any():
        columns = [
            m
            for m, bad in zip(metric_names, ~np.isfinite(values[broken]).all(axis=0), strict=True)
            if bad
        ]
        raise ValueError(
            f"{int(broken.sum())} evaluated rows have missing or infinite values in {columns}"
        )

    stat_rows: list[dict[str, object]] = []
    reason_rows: list[dict[str, object]] = []
    n_rows: dict[str, int] = {}
    n_evaluated: dict[str, int] = {}
    for group in GROUPS:
        in_group = (frame["side"] == group) if group != OVERALL else pd.Series(True, frame.index)
        chosen = (in_group & evaluated).to_numpy()
        n_rows[group] = int(in_group.sum())
        n_evaluated[group] = int(chosen.sum())
        for j, metric in enumerate(metric_names):
            stat_rows.append({"group": group, "metric": metric, **_stats(values[chosen, j])})
        counts = reason[in_group & ~evaluated].astype(str).value_counts()
        for text, count in sorted(counts.items(), key=lambda item: (-item[1], item[0])):
            reason_rows.append({"group": group, "reason": text, "count": int(count)})

    table = pd.DataFrame(stat_rows, columns=["group", "metric", *STAT_COLUMNS])
    table["n"] = table["n"].astype(np.int64)
    unevaluated = pd.DataFrame(reason_rows, columns=["group", "reason", "count"])
    unevaluated["count"] = unevaluated["count"].astype(np.int64)
    return MetricSummary(
        table=table, unevaluated=unevaluated, n_rows=n_rows, n_evaluated=n_evaluated
    )
