"""Trajectory fidelity of one player-round under the two protocols of docs/metrics.md.

Inputs are the original and simulated positions (metres) at the data frames of one round, on the
same frame clock, each with its alive mask. `O` is the original at its alive frames, `S` the
simulation at its alive frames, `k` the frames alive in both.

* Protocol "clock" (primary): `mean_dist`, `rmse`, `max_dist`, `final_dist` compare O_t and S_t
  frame by frame over `k`; `dtw` (mean cost per matched pair) and `frechet_2d` (x-y) compare all
  alive frames of each.
* Protocol "paper": O and S are each resampled to `PAPER_LENGTH` points by linear interpolation
  over normalised index, then `paper_euclidean` = ‖A − B‖_F / L, `paper_rmse` per coordinate,
  `paper_dtw` and `paper_frechet_2d`.

A player-round is evaluated only when every metric is defined: at least `MIN_ALIVE_FRAMES` alive
frames in each trajectory, at least one frame alive in both, and finite positions at alive frames.
Otherwise all metrics are NaN and `reason` says why, so every metric is averaged over the same
player-rounds and nothing is dropped silently.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping
from dataclasses import dataclass

import numpy as np
import pandas as pd

from decoy_cli.metrics.distances import curve_kernel
from decoy_cli.metrics.fastdtw_metric import fastdtw_mean
from decoy_cli.metrics.trajectory_kernel import (
    FEW_ORIGINAL,
    FEW_SIMULATED,
    NON_FINITE,
    NONE_IN_BOTH,
    OK,
    metric_values,
    resample_points,
)

METRIC_NAMES_CLOCK = ("mean_dist", "rmse", "max_dist", "dtw", "frechet_2d", "final_dist")
METRIC_NAMES_PAPER = ("paper_euclidean", "paper_rmse", "paper_dtw", "paper_frechet_2d")
METRIC_NAMES = METRIC_NAMES_CLOCK + METRIC_NAMES_PAPER
"""All trajectory metrics, clock protocol first, in the order of docs/metrics.md."""

FASTDTW_METRIC = "paper_dtw_fastdtw"
"""The paper's DTW computed with the `fastdtw` package (`fastdtw_metric`); only on request."""

ALL_METRIC_NAMES = (*METRIC_NAMES, FASTDTW_METRIC)
"""Every trajectory metric a table may hold, in display order."""

PAPER_PROTOCOL_NAMES = (*METRIC_NAMES_PAPER, FASTDTW_METRIC)
"""The metrics of protocol "paper", `paper_dtw_fastdtw` included."""


def metric_names(fastdtw: bool) -> tuple[str, ...]:
    """The trajectory metrics computed, with or without `paper_dtw_fastdtw`."""
    return ALL_METRIC_NAMES if fastdtw else METRIC_NAMES


PAPER_LENGTH = 451
"""Number of points each alive trajectory is resampled to in the paper protocol."""

MIN_ALIVE_FRAMES = 2
"""Fewest alive frames a trajectory needs (interpolation needs two points)."""

_REASONS = {
    FEW_ORIGINAL: f"original alive in fewer than {MIN_ALIVE_FRAMES} frames",
    FEW_SIMULATED: f"simulated alive in fewer than {MIN_ALIVE_FRAMES} frames",
    NONE_IN_BOTH: "no frame alive in both",
    NON_FINITE: "non-finite position at an alive frame",
}


@dataclass(frozen=True)
class TrajectoryMetrics:
    """The metrics of one player-round; all NaN with a `reason` when it cannot be evaluated."""

    values: dict[str, float]
    reason: str | None = None


@dataclass(frozen=True)
class PlayerRound:
    """One player's original and simulated trajectory in one round, on the data frame clock.

    `key` holds the identifying columns of the output row (e.g. match, round, player, side).
    """

    key: Mapping[str, object]
    original: np.ndarray  # (F, 3) metres
    original_alive: np.ndarray  # (F,) bool
    simulated: np.ndarray  # (F, 3) metres
    simulated_alive: np.ndarray  # (F,) bool


def resample(points: np.ndarray, length: int = PAPER_LENGTH) -> np.ndarray:
    """Linearly resample an (n, d) polyline, n >= 2, to `length` points over normalised index.

    Output point q sits at fractional index q·(n−1)/(length−1) of the input, so the first and
    last points are kept exactly.
    """
    points = np.ascontiguousarray(points, dtype=np.float64)
    if points.ndim != 2:
        raise ValueError(f"resampling needs an (n, d) array of points, got shape {points.shape}")
    n = points.shape[0]
    if n < 2 or length < 2:
        raise ValueError(f"resampling needs at least 2 input and output points, got {n}, {length}")
    return resample_points(points, length)


def _validated(
    original: np.ndarray,
    original_alive: np.ndarray,
    simulated: np.ndarray,
    simulated_alive: np.ndarray,
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Check shapes (one frame clock, 3-D points, boolean masks) and return float/bool arrays."""
    original = np.ascontiguousarray(original, dtype=np.float64)  # one compiled layout
    simulated = np.ascontiguousarray(simulated, dtype=np.float64)
    original_alive = np.asarray(original_alive)
    simulated_alive = np.asarray(simulated_alive)
    if original.ndim != 2 or original.shape[1] != 3 or simulated.shape != original.shape:
        raise ValueError(
            "original and simulated must be (F, 3) arrays on the same frame clock, "
            f"got {original.shape} and {simulated.shape}"
        )
    frames = original.shape[0]
    for name, mask in (("original_alive", original_alive), ("simulated_alive", simulated_alive)):
        if mask.dtype != np.bool_ or mask.shape != (frames,):
            raise ValueError(
                f"{name} must be a boolean ({frames},) array, got {mask.dtype} {mask.shape}"
            )
    return original, original_alive, simulated, simulated_alive


def _not_evaluable(reason: str, fastdtw: bool) -> TrajectoryMetrics:
    return TrajectoryMetrics(
        values=dict.fromkeys(metric_names(fastdtw), float("nan")), reason=reason
    )


def trajectory_metrics(
    original: np.ndarray,
    original_alive: np.ndarray,
    simulated: np.ndarray,
    simulated_alive: np.ndarray,
    *,
    fastdtw: bool = False,
) -> TrajectoryMetrics:
    """All ten trajectory metrics (both protocols) of one player-round; see the module doc.
    With `fastdtw`, also `paper_dtw_fastdtw` (the paper's FastDTW on the paper protocol).

    Raises ValueError when the arrays are not (F, 3) positions with (F,) boolean masks.
    """
    original, original_alive, simulated, simulated_alive = _validated(
        original, original_alive, simulated, simulated_alive
    )
    outcome, values, o, s, a, b = metric_values(
        original, original_alive, simulated, simulated_alive, PAPER_LENGTH, MIN_ALIVE_FRAMES
    )
    if outcome != OK:
        return _not_evaluable(_REASONS[outcome], fastdtw)
    named = dict(zip(METRIC_NAMES, values.tolist(), strict=True))  # curve distances NaN so far
    clock_total, clock_steps, named["frechet_2d"] = curve_kernel(o, s, 2)
    paper_total, paper_steps, named["paper_frechet_2d"] = curve_kernel(a, b, 2)
    named["dtw"] = clock_total / clock_steps
    named["paper_dtw"] = paper_total / paper_steps
    if fastdtw:
        named[FASTDTW_METRIC] = fastdtw_mean(a, b)
    return TrajectoryMetrics(values=named)


def trajectory_metrics_frame(player_rounds: Iterable[PlayerRound]) -> pd.DataFrame:
    """One row per player-round: key columns, `METRIC_NAMES`, `reason` (missing if evaluated).

    The key columns of all player-rounds must have the same names; they come first, in the
    order of the first key.
    """
    rows: list[dict[str, object]] = []
    key_names: list[str] | None = None
    for item in player_rounds:
        names = list(item.key)
        if key_names is None:
            clash = set(names) & {*METRIC_NAMES, "reason"}
            if clash:
                raise ValueError(f"player-round key uses reserved column names: {sorted(clash)}")
            key_names = names
        elif set(names) != set(key_names):
            raise ValueError(f"player-round keys differ: {sorted(names)} vs {sorted(key_names)}")
        result = trajectory_metrics(
            item.original, item.original_alive, item.simulated, item.simulated_alive
        )
        rows.append({**item.key, **result.values, "reason": result.reason})
    return pd.DataFrame(rows, columns=[*(key_names or []), *METRIC_NAMES, "reason"])
