"""Bomb fidelity over many rounds, as defined in docs/metrics.md.

Input: one row per replayed round with the bomb columns of `decoy_cli.replay.bomb_fidelity`
(`plant_data`, `plant_replay`, `plant_time_error_s`, `plant_site_data`, `plant_site_replay`,
`plant_position_error_m`, `defuse_data`, `defuse_replay`, `defuse_time_error_s`,
`bomb_anomalies`, and `bomb_recorded`, which selects the rounds whose data records the bomb).
Output: `BombMetrics`, the values with the number of rounds each is over (NaN with a reason when
none), and the plant and defuse confusions (rows: the data, columns: the replay).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
import pandas as pd

from decoy_cli.metrics.bootstrap import Interval, RoundBootstrap

BOMB_METRIC_NAMES = (
    "plant_agreement",
    "plant_time_error_median_s",
    "plant_time_error_p95_s",
    "plant_site_agreement",
    "plant_position_error_median_m",
    "plant_position_error_p95_m",
    "defuse_agreement",
    "defuse_time_error_median_s",
    "defuse_time_error_p95_s",
)
"""The aggregate bomb metrics, in table order. Time errors are of |replay − data|."""


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
    values: dict[str, float] = {}
    counts: dict[str, int] = {}
    reasons: dict[str, str] = {}

    def put(name: str, value: float, n: int, why: str) -> None:
        values[name], counts[name] = (value, n) if n else (float("nan"), 0)
        if not n:
            reasons[name] = why

    plant_d = _flag(rows, "plant_data")
    plant_r = _flag(rows, "plant_replay")
    put("plant_agreement", float(np.mean(plant_d == plant_r)), len(rows), "no round with bomb data")
    _errors(put, rows, "plant_time_error", "s", "no round planted in both")
    both = rows[plant_d & plant_r]
    put(
        "plant_site_agreement",
        float(np.mean(both["plant_site_data"] == both["plant_site_replay"])),
        len(both),
        "no round planted in both",
    )
    _errors(put, rows, "plant_position_error", "m", "no plant position in the data")
    defuse_d = _flag(rows, "defuse_data")
    defuse_r = _flag(rows, "defuse_replay")
    planted = rows[plant_d | plant_r]
    agree = defuse_d[plant_d | plant_r] == defuse_r[plant_d | plant_r]
    put("defuse_agreement", float(np.mean(agree)), len(planted), "no round with a plant")
    _errors(put, rows, "defuse_time_error", "s", "no round defused in both")
    anomalies = rows["bomb_anomalies"].fillna("").astype(str) if len(rows) else pd.Series([])
    return BombMetrics(
        values=values,
        intervals=_intervals(rows, plant_d, plant_r, defuse_d, defuse_r, seed),
        counts=counts,
        reasons=reasons,
        n_rounds=len(rows),
        plant_confusion=_confusion(plant_d, plant_r, "planted"),
        defuse_confusion=_confusion(
            defuse_d[plant_d | plant_r], defuse_r[plant_d | plant_r], "defused"
        ),
        anomalies=int((anomalies != "").sum()),
    )


def _intervals(
    rows: pd.DataFrame,
    plant_d: np.ndarray,
    plant_r: np.ndarray,
    defuse_d: np.ndarray,
    defuse_r: np.ndarray,
    seed: int,
) -> dict[str, Interval]:
    """The interval of each metric: agreements are means of per-round indicators, the time and
    position errors' medians are medians of per-round values; a p95 gets none."""
    boot = RoundBootstrap(len(rows), seed=seed)
    index = np.arange(len(rows))
    planted = plant_d | plant_r
    both = plant_d & plant_r
    same_site = np.zeros(len(rows), bool)
    if len(rows):
        same_site = (rows["plant_site_data"] == rows["plant_site_replay"]).to_numpy()
    tail = Interval(np.nan, np.nan, "no interval for a p95")

    def median(name: str) -> Interval:
        values = np.zeros(0)
        if len(rows):
            values = np.abs(pd.to_numeric(rows[name], errors="coerce").to_numpy(np.float64))
        return boot.interval(values, index, "median")

    def share(agree: np.ndarray, over: np.ndarray) -> Interval:
        return boot.interval(agree[over].astype(np.float64), index[over], "mean")

    everywhere = np.ones(len(rows), bool)
    return {
        "plant_agreement": share(plant_d == plant_r, everywhere),
        "plant_time_error_median_s": median("plant_time_error_s"),
        "plant_time_error_p95_s": tail,
        "plant_site_agreement": share(same_site, both),
        "plant_position_error_median_m": median("plant_position_error_m"),
        "plant_position_error_p95_m": tail,
        "defuse_agreement": share(defuse_d == defuse_r, planted),
        "defuse_time_error_median_s": median("defuse_time_error_s"),
        "defuse_time_error_p95_s": tail,
    }


def _flag(rows: pd.DataFrame, column: str) -> np.ndarray:
    return rows[column].fillna(False).astype(bool).to_numpy() if len(rows) else np.zeros(0, bool)


Put = Callable[[str, float, int, str], None]
"""Records one metric: name, value, rounds it is over, why it is NaN when over none."""


def _errors(put: Put, rows: pd.DataFrame, stem: str, unit: str, why: str) -> None:
    """Median and p95 of |error| of one column over the rounds where it is defined."""
    column = f"{stem}_{unit}"
    error = np.zeros(0)
    if len(rows):
        error = np.abs(pd.to_numeric(rows[column], errors="coerce").to_numpy(np.float64))
    error = error[np.isfinite(error)]
    n = len(error)
    put(f"{stem}_median_{unit}", float(np.median(error)) if n else np.nan, n, why)
    put(f"{stem}_p95_{unit}", float(np.percentile(error, 95)) if n else np.nan, n, why)


def _confusion(data: np.ndarray, replay: np.ndarray, what: str) -> pd.DataFrame:
    """2×2 counts: rows the data, columns the replay, labels `what` / not `what`."""
    labels = [what, f"not {what}"]
    table = pd.DataFrame(
        0, index=pd.Index(labels, name="data"), columns=pd.Index(labels, name="replay")
    )
    for d, r in zip(data, replay, strict=True):
        table.loc[labels[0 if d else 1], labels[0 if r else 1]] += 1
    return table
