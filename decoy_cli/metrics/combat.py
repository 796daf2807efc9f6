"""Combat and outcome fidelity of full rounds (both teams), as defined in docs/metrics.md.

* `hp_metrics`: `hp_corr` (Pearson over pooled player-frames on the common clock), the paper's
  weaker `paper_hp_corr` (Pearson of the two population-mean HP curves) and `hp_rmse`.
* `death_time_metrics`: `death_time_corr` and `death_time_mae_s` over players who died in both,
  with the confusion counts.
* `outcome_metrics`: `outcome_agreement`, `end_reason_agreement` and their confusion matrices.

Inputs are plain arrays or lists, pooled by the caller over the evaluated rounds. A metric that is
not defined (no data, a constant series) is NaN and its name maps to the reason in `reasons`.
Malformed input (mismatched lengths, non-finite values) raises ValueError.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import pandas as pd
from numpy.typing import ArrayLike

HP_METRIC_NAMES = ("hp_corr", "paper_hp_corr", "hp_rmse")
DEATH_TIME_METRIC_NAMES = ("death_time_corr", "death_time_mae_s")
OUTCOME_METRIC_NAMES = ("outcome_agreement", "end_reason_agreement")
DEATH_COUNT_NAMES = ("died_both", "died_only_original", "died_only_simulated", "died_neither")


@dataclass(frozen=True)
class HpMetrics:
    """HP fidelity; `reasons` maps each NaN metric to why it is not defined."""

    values: dict[str, float]
    reasons: dict[str, str]
    n_player_frames: int
    n_frame_times: int  # distinct frame indices = length of the population-mean curves


@dataclass(frozen=True)
class DeathTimeMetrics:
    """Death-time fidelity over players who died in both, plus who died where."""

    values: dict[str, float]
    reasons: dict[str, str]
    counts: dict[str, int]  # keys DEATH_COUNT_NAMES


@dataclass(frozen=True)
class OutcomeMetrics:
    """Round outcome fidelity; confusion rows are the original label, columns the simulated."""

    values: dict[str, float]
    reasons: dict[str, str]
    n_rounds: int
    winner_confusion: pd.DataFrame
    end_reason_confusion: pd.DataFrame | None  # None when end reasons were not given


def pearson(x: np.ndarray, y: np.ndarray) -> tuple[float, str | None]:
    """Pearson correlation of two equal-length series, or (NaN, reason) when it is undefined."""
    if x.shape[0] < 2:
        return float("nan"), "fewer than 2 values"
    if np.ptp(x) == 0:
        return float("nan"), "original series is constant"
    if np.ptp(y) == 0:
        return float("nan"), "simulated series is constant"
    xc = x - x.mean()
    yc = y - y.mean()
    r = float(np.dot(xc, yc) / np.sqrt(np.dot(xc, xc) * np.dot(yc, yc)))
    return min(1.0, max(-1.0, r)), None


def _vector(values: ArrayLike, name: str) -> np.ndarray:
    """A 1-D float64 array (None becomes NaN)."""
    array = np.asarray(values, dtype=np.float64)
    if array.ndim != 1:
        raise ValueError(f"{name} must be one-dimensional, got shape {array.shape}")
    return array


def _same_length(*arrays: Sequence[object] | np.ndarray) -> int:
    lengths = {len(a) for a in arrays}
    if len(lengths) != 1:
        raise ValueError(f"inputs must have the same length, got lengths {sorted(lengths)}")
    return lengths.pop()


def _finish(reasons: dict[str, str | None]) -> dict[str, str]:
    """Keep the reasons of the metrics that are NaN (those with a reason)."""
    return {k: r for k, r in reasons.items() if r is not None}


def hp_metrics(
    original_hp: ArrayLike, simulated_hp: ArrayLike, frame_index: ArrayLike
) -> HpMetrics:
    """HP fidelity over pooled player-frames (dead players count with 0 HP).

    `frame_index[i]` is the data frame number since round start of player-frame i; it defines
    the population-mean HP curves (mean over all player-frames with the same frame number).
    """
    o = _vector(original_hp, "original_hp")
    s = _vector(simulated_hp, "simulated_hp")
    frames = np.asarray(frame_index)
    n = _same_length(o, s, frames)
    if frames.ndim != 1 or (n and not np.issubdtype(frames.dtype, np.integer)):
        raise ValueError("frame_index must be a one-dimensional integer array")
    if not (np.isfinite(o).all() and np.isfinite(s).all()):
        raise ValueError("HP values must be finite")

    reasons: dict[str, str | None] = {}
    values: dict[str, float] = {}
    values["hp_corr"], reasons["hp_corr"] = pearson(o, s)
    times, inverse = np.unique(frames, return_inverse=True)
    counts = np.bincount(inverse, minlength=times.size)
    mean_o = np.bincount(inverse, weights=o, minlength=times.size) / np.maximum(counts, 1)
    mean_s = np.bincount(inverse, weights=s, minlength=times.size) / np.maximum(counts, 1)
    values["paper_hp_corr"], reasons["paper_hp_corr"] = pearson(mean_o, mean_s)
    if n:
        values["hp_rmse"], reasons["hp_rmse"] = float(np.sqrt(np.mean((o - s) ** 2))), None
    else:
        values["hp_rmse"], reasons["hp_rmse"] = float("nan"), "no player-frames"
    return HpMetrics(
        values=values,
        reasons=_finish(reasons),
        n_player_frames=n,
        n_frame_times=int(times.size),
    )


def death_time_metrics(
    original_death_s: ArrayLike, simulated_death_s: ArrayLike
) -> DeathTimeMetrics:
    """Death-time fidelity; one entry per player-round: seconds from round start, NaN = alive."""
    o = _vector(original_death_s, "original_death_s")
    s = _vector(simulated_death_s, "simulated_death_s")
    _same_length(o, s)
    for name, times in (("original_death_s", o), ("simulated_death_s", s)):
        known = times[~np.isnan(times)]
        if not (np.isfinite(known).all() and (known >= 0).all()):
            raise ValueError(f"{name} must be non-negative seconds or NaN (survived)")
    died_o = ~np.isnan(o)
    died_s = ~np.isnan(s)
    both = died_o & died_s
    counts = {
        "died_both": int(both.sum()),
        "died_only_original": int((died_o & ~died_s).sum()),
        "died_only_simulated": int((~died_o & died_s).sum()),
        "died_neither": int((~died_o & ~died_s).sum()),
    }
    reasons: dict[str, str | None] = {}
    values: dict[str, float] = {}
    if both.any():
        values["death_time_corr"], reasons["death_time_corr"] = pearson(o[both], s[both])
        values["death_time_mae_s"] = float(np.mean(np.abs(o[both] - s[both])))
    else:
        values["death_time_corr"] = values["death_time_mae_s"] = float("nan")
        reasons["death_time_corr"] = reasons["death_time_mae_s"] = "no player died in both"
    return DeathTimeMetrics(values=values, reasons=_finish(reasons), counts=counts)


def _labels(values: Sequence[str], name: str) -> list[str]:
    labels = list(values)
    if not all(isinstance(v, str) and v for v in labels):
        raise ValueError(f"{name} must be non-empty strings")
    return labels


def confusion_matrix(original: Sequence[str], simulated: Sequence[str]) -> pd.DataFrame:
    """Counts of (original label, simulated label); square over the sorted union of labels."""
    labels = sorted(set(original) | set(simulated))
    table = pd.crosstab(
        pd.Series(list(original), dtype=object), pd.Series(list(simulated), dtype=object)
    )
    table = table.reindex(index=labels, columns=labels, fill_value=0).astype(np.int64)
    table.index.name = "original"
    table.columns.name = "simulated"
    return table


def outcome_metrics(
    original_winner: Sequence[str],
    simulated_winner: Sequence[str],
    original_end_reason: Sequence[str] | None = None,
    simulated_end_reason: Sequence[str] | None = None,
) -> OutcomeMetrics:
    """Share of rounds with the same winning side (and the same end reason, when given)."""
    ow = _labels(original_winner, "original_winner")
    sw = _labels(simulated_winner, "simulated_winner")
    n = _same_length(ow, sw)
    if (original_end_reason is None) != (simulated_end_reason is None):
        raise ValueError("give the end reasons of both the original and the simulated rounds")
    reasons: dict[str, str | None] = {}
    values: dict[str, float] = {}
    if n:
        values["outcome_agreement"] = float(np.mean([a == b for a, b in zip(ow, sw, strict=True)]))
    else:
        values["outcome_agreement"], reasons["outcome_agreement"] = float("nan"), "no rounds"
    end_confusion = None
    if original_end_reason is None or simulated_end_reason is None:
        values["end_reason_agreement"] = float("nan")
        reasons["end_reason_agreement"] = "end reasons not given"
    else:
        oe = _labels(original_end_reason, "original_end_reason")
        se = _labels(simulated_end_reason, "simulated_end_reason")
        _same_length(ow, oe, se)
        if n:
            agree = [a == b for a, b in zip(oe, se, strict=True)]
            values["end_reason_agreement"] = float(np.mean(agree))
        else:
            values["end_reason_agreement"] = float("nan")
            reasons["end_reason_agreement"] = "no rounds"
        end_confusion = confusion_matrix(oe, se)
    return OutcomeMetrics(
        values=values,
        reasons=_finish(reasons),
        n_rounds=n,
        winner_confusion=confusion_matrix(ow, sw),
        end_reason_confusion=end_confusion,
    )
