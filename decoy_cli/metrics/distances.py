"""Exact curve distances: dynamic time warping (DTW) and the discrete Fréchet distance.

Both take two point sequences of shape (n, d) and (m, d) (any dimension d >= 1) and use the
Euclidean distance between points as the point cost. Both are exact O(n·m) dynamic programs
compiled with numba that compute point costs on the fly and never build an n x m matrix: Fréchet
keeps one row (O(m) memory), DTW three anti-diagonals plus transposed copies (O(n + m) memory).

DTW uses the steps (1,0), (0,1) and (1,1) from (0, 0) to (n-1, m-1). `dtw` returns the minimum
total cost and the number of steps (matched pairs, i.e. cells) on an optimal warping path; the
project's DTW metric is total / steps (see docs/metrics.md).

Tie-breaking (the step count, hence the metric, depends on it): among the warping paths of
minimum total cost, the one with the fewest steps is chosen. Costs that differ only by the
floating-point rounding of their sums (relative difference <= `TIE_RTOL`) count as equal, so the
choice does not depend on the order in which equal real costs were added. The rule is applied cell
by cell: a cell takes, among its predecessors whose accumulated cost is within the tolerance of
the cheapest, the one with the fewest steps, and among those the lowest cost. Because (cost,
steps) add up along a path, this yields the lexicographic (cost, steps) minimum over all paths,
i.e. the fewest-steps path among the cheapest ones. The returned cost and step count belong to
the same path. The result is symmetric: dtw(a, b) == dtw(b, a).

Empty input, mismatched dimensions and non-finite coordinates raise `ValueError`.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

TIE_RTOL = 1e-12
"""Accumulated DTW costs within this relative difference count as a tie (rounding of the sums)."""

_NO_PATH = np.iinfo(np.int64).max


@njit(cache=True, nogil=True)
def _dtw_kernel(a: np.ndarray, b: np.ndarray, rtol: float) -> tuple[float, int]:
    """Minimum DTW total cost and the fewest steps among paths of that cost (see module doc).

    Cells are swept by anti-diagonals s = i + j: a cell depends only on the two previous
    diagonals, so the loop over a diagonal has no serial dependency and vectorises. Diagonals are
    stored by row index i at buffer position i + 1; position 0 (i = -1) and the position after a
    diagonal's last cell stay +inf, so border cells see missing predecessors as infinitely costly.
    """
    n, d = a.shape
    m = b.shape[0]
    a_t = np.ascontiguousarray(a.T)  # (d, n)
    b_rev_t = np.ascontiguousarray(b[::-1].T)  # (d, m); column m-1-j is point j
    cost_pp = np.full(n + 2, math.inf)  # diagonal s - 2
    cost_p = np.full(n + 2, math.inf)  # diagonal s - 1
    cost_c = np.full(n + 2, math.inf)  # diagonal s
    steps_pp = np.zeros(n + 2, dtype=np.int64)
    steps_p = np.zeros(n + 2, dtype=np.int64)
    steps_c = np.zeros(n + 2, dtype=np.int64)
    dist = np.empty(n, dtype=np.float64)
    for s in range(n + m - 1):
        lo = max(0, s - m + 1)
        hi = min(s, n - 1)
        count = hi - lo + 1
        offset = m - 1 - s  # cell (i, s - i) pairs a_t[:, i] with b_rev_t[:, i + offset]
        for t in range(count):
            dist[t] = 0.0
        for k in range(d):
            a_k = a_t[k]
            b_k = b_rev_t[k]
            for t in range(count):
                diff = a_k[lo + t] - b_k[lo + t + offset]
                dist[t] += diff * diff
        if s == 0:
            cost_c[1] = math.sqrt(dist[0])
            steps_c[1] = 1
        else:
            for t in range(count):
                p = lo + t + 1
                diag_cost = cost_pp[p - 1]
                up_cost = cost_p[p - 1]
                left_cost = cost_p[p]
                best = min(diag_cost, min(up_cost, left_cost))
                limit = best + rtol * best
                diag_steps = steps_pp[p - 1] if diag_cost <= limit else _NO_PATH
                up_steps = steps_p[p - 1] if up_cost <= limit else _NO_PATH
                left_steps = steps_p[p] if left_cost <= limit else _NO_PATH
                sel_steps = min(diag_steps, min(up_steps, left_steps))
                sel_cost = min(
                    diag_cost if diag_steps == sel_steps else math.inf,
                    min(
                        up_cost if up_steps == sel_steps else math.inf,
                        left_cost if left_steps == sel_steps else math.inf,
                    ),
                )
                cost_c[p] = sel_cost + math.sqrt(dist[t])
                steps_c[p] = sel_steps + 1
        cost_c[hi + 2] = math.inf
        cost_pp, cost_p, cost_c = cost_p, cost_c, cost_pp
        steps_pp, steps_p, steps_c = steps_p, steps_c, steps_pp
    return float(cost_p[n]), int(steps_p[n])


@njit(cache=True, nogil=True)
def _frechet_kernel(a: np.ndarray, b: np.ndarray) -> float:
    """Discrete Fréchet distance: min over couplings of the max point distance.

    Works on squared distances (min and max commute with the monotone square root, so the result
    is the same) and takes one square root at the end. One row of length m is kept.
    """
    n, d = a.shape
    m = b.shape[0]
    b_t = np.ascontiguousarray(b.T)  # (d, m)
    sq = np.empty(m, dtype=np.float64)
    row = np.empty(m, dtype=np.float64)
    for i in range(n):
        for j in range(m):
            sq[j] = 0.0
        for k in range(d):
            a_ik = a[i, k]
            b_k = b_t[k]
            for j in range(m):
                diff = a_ik - b_k[j]
                sq[j] += diff * diff
        if i == 0:
            acc = 0.0
            for j in range(m):
                acc = max(acc, sq[j])
                row[j] = acc
            continue
        diag = row[0]
        row[0] = max(row[0], sq[0])
        left = row[0]
        for j in range(1, m):
            up = row[j]
            # max(min(diag, up, left), c) split so only two operations depend on `left`.
            left = min(max(min(diag, up), sq[j]), max(left, sq[j]))
            row[j] = left
            diag = up
    return math.sqrt(row[m - 1])


def _as_curves(a: np.ndarray, b: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Validate two curves and return them as C-contiguous float64 (n, d) and (m, d) arrays."""
    a = np.ascontiguousarray(a, dtype=np.float64)
    b = np.ascontiguousarray(b, dtype=np.float64)
    if a.ndim != 2 or b.ndim != 2:
        raise ValueError(
            f"curves must be 2-D (points, dims) arrays, got shapes {a.shape} and {b.shape}"
        )
    if a.shape[0] == 0 or b.shape[0] == 0:
        raise ValueError(f"curves must have at least one point, got {a.shape[0]} and {b.shape[0]}")
    if a.shape[1] != b.shape[1] or a.shape[1] == 0:
        raise ValueError(f"curves must share a dimension >= 1, got {a.shape[1]} and {b.shape[1]}")
    if not (np.isfinite(a).all() and np.isfinite(b).all()):
        raise ValueError("curves must not contain NaN or infinite coordinates")
    return a, b


def dtw(a: np.ndarray, b: np.ndarray) -> tuple[float, int]:
    """Exact DTW of two curves: (minimum total cost, steps on the chosen optimal warping path).

    Point cost is the Euclidean distance; steps (1,0), (0,1), (1,1); ties as in the module doc.
    The mean cost per matched pair (the project's `dtw` metric) is `total / steps`.
    """
    a, b = _as_curves(a, b)
    total, steps = _dtw_kernel(a, b, TIE_RTOL)
    return float(total), int(steps)


def dtw_mean(a: np.ndarray, b: np.ndarray) -> float:
    """DTW total cost divided by the number of steps on the optimal warping path."""
    total, steps = dtw(a, b)
    return total / steps


def frechet(a: np.ndarray, b: np.ndarray) -> float:
    """Exact discrete Fréchet distance of two curves (Euclidean point distance)."""
    a, b = _as_curves(a, b)
    return float(_frechet_kernel(a, b))
