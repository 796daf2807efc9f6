"""Bomb fidelity over many rounds, as defined in docs/metrics.md.

Input: one row per replayed round with the bomb columns of `decoy_cli.replay.bomb_fidelity`
(`plant_data`, `plant_replay`, `plant_time_error_s`, `plant_site_data`, `plant_site_replay`,
`plant_position_error_m`, `defuse_data`, `defuse_replay`, `defuse_time_error_s`,
`bomb_anomalies`, and `bomb_recorded`, which selects the rounds whose data records the bomb).
Output: `BombMetrics`, the values with the number of rounds each is over (NaN with a reason when
none), and the plant and defuse confusions (rows: the data, columns: the replay).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pandas as pd

from decoy_cli.metrics.bootstrap import Interval, RoundBootstrap
from decoy_cli.metrics.combat import confusion_matrix

BOMB_METRIC_NAMES = (
    "plant_agreement",
    "plants_completed_share",
    "plants_replay_only",
    "plant_time_error_median_s",
    "plant_time_error_mean_abs_s",
    "plant_time_error_p95_s",
    "plant_site_agreement",
    "plant_position_error_median_m",
    "plant_position_error_p95_m",
    "defuse_agreement",
    "defuse_time_error_median_s",
    "defuse_time_error_mean_abs_s",
    "defuse_time_error_p95_s",
)
"""The aggregate bomb metrics, in table order (docs/metrics.md): the time errors' median is of
the signed error (replay − data), their mean and p95 of its absolute value."""


@dataclass(frozen=True)
class BombMetrics:
    """Bomb fidelity over the rounds whose data records the bomb."""

    values: dict[str, float]
    intervals: dict[str, Interval]
    """95% bootstrap interval of each metric, resampling rounds (`metrics.bootstrap`)."""
    counts: dict[str, int]
    """Rounds each metric is over (`BOMB_METRIC_NAMES` keys)."""
    reasons: dict[str, str]
    """Why a NaN metric is not defined."""
    n_rounds: int
    plant_confusion: pd.DataFrame
    defuse_confusion: pd.DataFrame
    anomalies: int
    """Rounds with at least one anomaly in their bomb data."""

    def table(self) -> pd.DataFrame:
        """One row per metric: value, rounds it is over, its interval, and why the value or
        the interval is missing when one is."""
        return pd.DataFrame(
            {
                "metric": list(BOMB_METRIC_NAMES),
                "value": [self.values[name] for name in BOMB_METRIC_NAMES],
                "rounds": [self.counts[name] for name in BOMB_METRIC_NAMES],
                "low": [self.intervals[name].low for name in BOMB_METRIC_NAMES],
                "high": [self.intervals[name].high for name in BOMB_METRIC_NAMES],
                "note": [
                    self.reasons.get(name) or self.intervals[name].note
                    for name in BOMB_METRIC_NAMES
                ],
            }
        )


def bomb_metrics(rounds: pd.DataFrame, *, seed: int = 0) -> BombMetrics:
    """Aggregate the bomb columns of `rounds` (module docstring); `seed` fixes the bootstrap."""
    rows = rounds[rounds["bomb_recorded"].astype(bool)] if len(rounds) else rounds
    plant_d, plant_r = _flag(rows, "plant_data"), _flag(rows, "plant_replay")
    defuse_d, defuse_r = _flag(rows, "defuse_data"), _flag(rows, "defuse_replay")
    both = plant_d & plant_r
    planted = plant_d | plant_r
    same_site = np.zeros(len(rows), bool)
    if len(rows):
        same_site = (rows["plant_site_data"] == rows["plant_site_replay"]).to_numpy()
    plant_error = _numbers(rows, "plant_time_error_s")
    position_error = _numbers(rows, "plant_position_error_m")
    defuse_error = _numbers(rows, "defuse_time_error_s")
    everywhere = np.ones(len(rows), bool)
    neither = "no round planted in both"
    # name: (per-round values, the rounds they are over, statistic, why empty)
    specs: dict[str, tuple[np.ndarray, np.ndarray, str, str]] = {
        "plant_agreement": (plant_d == plant_r, everywhere, "mean", "no round with bomb data"),
        "plants_completed_share": (plant_r, plant_d, "mean", "no plant in the data"),
        "plants_replay_only": (plant_r & ~plant_d, everywhere, "count", "no round with bomb data"),
        "plant_time_error_median_s": (plant_error, both, "median", neither),
        "plant_time_error_mean_abs_s": (
            np.abs(plant_error),
            both,
            "mean",
            neither,
        ),
        "plant_time_error_p95_s": (np.abs(plant_error), both, "p95", neither),
        "plant_site_agreement": (same_site, both, "mean", neither),
        "plant_position_error_median_m": (
            position_error,
            both & np.isfinite(position_error),
            "median",
            "no plant position",
        ),
        "plant_position_error_p95_m": (
            position_error,
            both & np.isfinite(position_error),
            "p95",
            "no plant position",
        ),
        "defuse_agreement": (defuse_d == defuse_r, planted, "mean", "no round with a plant"),
        "defuse_time_error_median_s": (
            defuse_error,
            defuse_d & defuse_r,
            "median",
            "no round defused in both",
        ),
        "defuse_time_error_mean_abs_s": (
            np.abs(defuse_error),
            defuse_d & defuse_r,
            "mean",
            "no round defused in both",
        ),
        "defuse_time_error_p95_s": (
            np.abs(defuse_error),
            defuse_d & defuse_r,
            "p95",
            "no round defused in both",
        ),
    }
    boot = RoundBootstrap(len(rows), seed=seed)
    index = np.arange(len(rows))
    values: dict[str, float] = {}
    counts: dict[str, int] = {}
    reasons: dict[str, str] = {}
    intervals: dict[str, Interval] = {}
    for name, (per_round, over, statistic, why) in specs.items():
        chosen = np.asarray(per_round, dtype=np.float64)[over]
        counts[name] = int(over.sum())
        if statistic == "count":
            values[name] = float(chosen.sum()) if len(chosen) else float("nan")
            intervals[name] = Interval(np.nan, np.nan, "a count")
        elif not len(chosen):
            values[name] = float("nan")
            intervals[name] = Interval(np.nan, np.nan, "")
        elif statistic == "p95":
            values[name] = float(np.percentile(chosen, 95))
            intervals[name] = Interval(np.nan, np.nan, "no interval for a p95")
        else:
            values[name] = float(np.mean(chosen) if statistic == "mean" else np.median(chosen))
            intervals[name] = boot.interval(chosen, index[over], statistic)
        if not len(chosen):
            reasons[name] = why
    anomalies = rows["bomb_anomalies"].fillna("").astype(str) if len(rows) else pd.Series([])
    return BombMetrics(
        values=values,
        intervals=intervals,
        counts=counts,
        reasons=reasons,
        n_rounds=len(rows),
        plant_confusion=_confusion(plant_d, plant_r, "planted"),
        defuse_confusion=_confusion(defuse_d[planted], defuse_r[planted], "defused"),
        anomalies=int((anomalies != "").sum()),
    )


def _flag(rows: pd.DataFrame, column: str) -> np.ndarray:
    return rows[column].fillna(False).astype(bool).to_numpy() if len(rows) else np.zeros(0, bool)


def _numbers(rows: pd.DataFrame, column: str) -> np.ndarray:
    """A column as float64 (NaN where empty)."""
    if not len(rows):
        return np.zeros(0)
    return pd.to_numeric(rows[column], errors="coerce").to_numpy(np.float64)


def _confusion(data: np.ndarray, replay: np.ndarray, what: str) -> pd.DataFrame:
    """2×2 counts: rows the data, columns the replay, labels `what` / not `what`."""
    labels = [what, f"not {what}"]
    table = confusion_matrix([labels[not d] for d in data], [labels[not r] for r in replay])
    table = table.reindex(index=labels, columns=labels, fill_value=0)
    table.index.name, table.columns.name = "data", "replay"
    return table
