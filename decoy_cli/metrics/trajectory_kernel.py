"""The numeric core of the trajectory metrics, compiled: one call per player-round.

`metric_values` computes the six metrics of docs/metrics.md that are not curve distances, and the
curves the DTW and Fréchet kernels then compare, from the validated arrays of one player-round
(trajectory.py validates, calls `distances.curve_kernel` on both protocols' curves and names the
values). Doing the masks, the per-frame distances, the resampling and the sums in one compiled
call removes the dozens of small numpy calls per player-round that otherwise cost a third of a
DTW. It does not call the curve kernels itself: numba's on-disk cache of a function does not
notice when a compiled function of another module that it calls changes.

The results equal those of the plain numpy expressions in docs/metrics.md: sums use numpy's
pairwise summation order (`pairwise_sum`, so means match `np.mean` bit for bit), resampling
reproduces `np.linspace`'s positions, and the per-frame distance adds x², y², z² in order as
`np.linalg.norm` does.
"""

from __future__ import annotations

import math

import numpy as np

from decoy_cli.compiled import njit_cached

OK = 0
FEW_ORIGINAL = 1
FEW_SIMULATED = 2
NONE_IN_BOTH = 3
NON_FINITE = 4
"""Outcome codes of `metric_values`: evaluated, or why not (trajectory.py words them)."""

_PAIRWISE_BLOCK = 128
"""numpy's PW_BLOCKSIZE: below it a sum is eight interleaved partial sums, above it halves."""


@njit_cached(nogil=True)
def pairwise_sum(values: np.ndarray) -> float:
    """Sum of a contiguous 1-D float64 array in numpy's pairwise order (equals `np.sum`)."""
    n = values.shape[0]
    if n < 8:
        total = -0.0
        for i in range(n):
            total += values[i]
        return total
    if n <= _PAIRWISE_BLOCK:
        r = values[:8].copy()
        full = n - n % 8
        for i in range(8, full, 8):
            for k in range(8):
                r[k] += values[i + k]
        total = (r[0] + r[1]) + (r[2] + r[3]) + ((r[4] + r[5]) + (r[6] + r[7]))
        for i in range(full, n):
            total += values[i]
        return total
    half = n // 2
    half -= half % 8
    return pairwise_sum(values[:half]) + pairwise_sum(values[half:])


@njit_cached(nogil=True)
def resample_points(points: np.ndarray, length: int) -> np.ndarray:
    """Linear resampling of an (n, d) polyline, n >= 2, to `length` points over normalised
    index, at the positions `np.linspace(0, n - 1, length)` gives."""
    n, d = points.shape
    step = (n - 1.0) / (length - 1)
    out = np.empty((length, d))
    for q in range(length):
        position = float(q) * step + 0.0 if q < length - 1 else n - 1.0
        lower = min(int(position), n - 2)
        frac = position - lower
        for k in range(d):
            out[q, k] = points[lower, k] * (1.0 - frac) + points[lower + 1, k] * frac
    return out


@njit_cached(nogil=True)
def metric_values(
    original: np.ndarray,
    original_alive: np.ndarray,
    simulated: np.ndarray,
    simulated_alive: np.ndarray,
    paper_length: int,
    min_alive: int,
) -> tuple[int, np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """(outcome code, values, O, S, A, B): the ten metrics in `METRIC_NAMES` order with the four
    curve distances (indices 3, 4, 8, 9) and everything when not evaluated left NaN; the alive
    curves O and S of the clock protocol and their resampled A and B of the paper protocol."""
    values = np.full(10, np.nan)
    o = original[original_alive]
    s = simulated[simulated_alive]
    empty = np.empty((0, 3))
    if o.shape[0] < min_alive:
        return FEW_ORIGINAL, values, o, s, empty, empty
    if s.shape[0] < min_alive:
        return FEW_SIMULATED, values, o, s, empty, empty
    both = original_alive & simulated_alive
    k = int(both.sum())
    if k == 0:
        return NONE_IN_BOTH, values, o, s, empty, empty
    if not (np.isfinite(o).all() and np.isfinite(s).all()):
        return NON_FINITE, values, o, s, empty, empty
    step = np.empty(k)
    index = 0
    for f in range(original.shape[0]):
        if both[f]:
            dx = original[f, 0] - simulated[f, 0]
            dy = original[f, 1] - simulated[f, 1]
            dz = original[f, 2] - simulated[f, 2]
            step[index] = math.sqrt(dx * dx + dy * dy + dz * dz)
            index += 1
    a = resample_points(o, paper_length)
    b = resample_points(s, paper_length)
    diff = (a - b).ravel()
    squared_diff = diff * diff
    diff_sum = pairwise_sum(squared_diff)
    values[0] = pairwise_sum(step) / k
    values[1] = math.sqrt(pairwise_sum(step * step) / k)
    values[2] = step.max()
    values[5] = step[k - 1]
    values[6] = math.sqrt(diff_sum) / paper_length
    values[7] = math.sqrt(diff_sum / squared_diff.shape[0])
    return OK, values, o, s, a, b
