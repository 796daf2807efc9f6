"""95% bootstrap intervals of the evaluation's aggregates, resampling whole rounds.

`trajectory_intervals` adds the intervals of every trajectory metric's mean and median (by side
and overall); `combat_intervals` those of the HP, death and outcome metrics: means of per-round
or per-player values directly, correlations and the HP RMSE from per-round sums
(`decoy_cli.metrics.bootstrap`). The seed is the run's, so a rerun gives the same intervals.
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from decoy_cli.metrics.bootstrap import Interval, RoundBootstrap, pearson_from_sums

INTERVAL_COLUMNS = ("mean_low", "mean_high", "median_low", "median_high", "interval_note")
"""Columns the intervals add to the trajectory table."""

COMBAT_INTERVAL_COLUMNS = ("low", "high", "interval_note")
"""Columns the intervals add to the combat table (of each metric's value)."""


def round_codes(frame: pd.DataFrame) -> tuple[np.ndarray, int]:
    """The round of each row (match and round number) as 0..R-1, and R."""
    codes, rounds = pd.factorize(frame["match"].astype(str) + "\0" + frame["round"].astype(str))
    return codes, len(rounds)


def trajectory_intervals(table: pd.DataFrame, players: pd.DataFrame, seed: int) -> pd.DataFrame:
    """The trajectory table with the intervals of each row's mean and median over the
    evaluated player-rounds of its group."""
    codes, count = round_codes(players)
    boot = RoundBootstrap(count, seed=seed)
    evaluated = players["reason"].isna().to_numpy()
    sides = players["side"].to_numpy()
    rows = []
    for group, metric in zip(table["group"], table["metric"], strict=True):
        chosen = evaluated & ((sides == group) if group != "all" else True)
        values = players[metric].to_numpy(np.float64)[chosen]
        mean = boot.interval(values, codes[chosen], "mean")
        median = boot.interval(values, codes[chosen], "median")
        rows.append((mean.low, mean.high, median.low, median.high, mean.note or median.note))
    intervals = pd.DataFrame(rows, columns=list(INTERVAL_COLUMNS), index=table.index)
    return pd.concat([table, intervals], axis=1)


def combat_intervals(
    combat: pd.DataFrame,
    players: pd.DataFrame,
    rounds: pd.DataFrame,
    hp_by_round: np.ndarray,
    seed: int,
) -> pd.DataFrame:
    """The combat table with the interval of each metric's value (`COMBAT_INTERVAL_COLUMNS`)."""
    boot = RoundBootstrap(len(rounds), seed=seed)
    round_index = np.arange(len(rounds))
    codes_of = {key: k for k, key in enumerate(zip(rounds["match"], rounds["round"], strict=True))}
    player_round = np.array(
        [codes_of.get(key, -1) for key in zip(players["match"], players["round"], strict=True)],
        dtype=np.int64,
    )
    o = players["death_time_original_s"].to_numpy(np.float64)
    s = players["death_time_replay_s"].to_numpy(np.float64)
    both = np.isfinite(o) & np.isfinite(s) & (player_round >= 0)
    death_sums = np.zeros((len(rounds), 6))
    for k, column in enumerate((np.ones_like(o), o, s, o * o, s * s, o * s)):
        np.add.at(death_sums[:, k], player_round[both], column[both])
    known = rounds["winner_original"].notna().to_numpy()
    reasons = rounds["reason_original"].notna().to_numpy()

    def agreement(original: str, replay: str, rows: np.ndarray, fill: str) -> Interval:
        same = rounds[original].astype(object).to_numpy() == (
            rounds[replay].astype(object).fillna(fill).to_numpy()
        )
        return boot.interval(same[rows].astype(np.float64), round_index[rows], "mean")

    intervals = {
        "hp_corr": boot.sums_interval(hp_by_round[:, :6], pearson_from_sums),
        "hp_rmse": boot.sums_interval(hp_by_round[:, [0, 6]], _rmse_from_sums),
        "paper_hp_corr": Interval(np.nan, np.nan, "no interval: a correlation of mean curves"),
        "death_time_corr": boot.sums_interval(death_sums, pearson_from_sums),
        "death_time_mae_s": boot.interval(np.abs(o - s)[both], player_round[both], "mean"),
        "outcome_agreement": agreement("winner_original", "winner_replay", known, "undecided"),
        "end_reason_agreement": agreement(
            "reason_original", "reason_replay", known & reasons, "end of the data"
        ),
        "decided_after_data": boot.interval(
            (rounds["played_out_s"].to_numpy(np.float64) > 0)[known].astype(np.float64),
            round_index[known],
            "mean",
        ),
    }
    rows = []
    for metric, value in zip(combat["metric"], combat["value"], strict=True):
        interval = intervals.get(metric, Interval(np.nan, np.nan, "no interval"))
        if not np.isfinite(value):
            interval = Interval(np.nan, np.nan, interval.note or "the value is undefined")
        rows.append((interval.low, interval.high, interval.note))
    extra = pd.DataFrame(rows, columns=list(COMBAT_INTERVAL_COLUMNS), index=combat.index)
    return pd.concat([combat, extra], axis=1)


def _rmse_from_sums(sums: np.ndarray) -> np.ndarray:
    """sqrt(Σd² / n) from rows of [n, Σd²]."""
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.where(sums[:, 0] > 0, np.sqrt(sums[:, 1] / sums[:, 0]), np.nan)
