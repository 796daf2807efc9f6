"""Exact curve distances: dynamic time warping (DTW) and the discrete Fréchet distance.

Both take two point sequences of shape (n, d) and (m, d), d from 1 to 3, and use the Euclidean
distance between points as the point cost. Both are exact O(n·m) dynamic programs compiled with
numba that compute point costs on the fly and never build an n x m matrix (O(n + m) memory).
`dtw_and_frechet` computes both in one sweep (the Fréchet distance possibly over the first
coordinates only, e.g. x-y of 3-D positions), which is what the trajectory metrics use.

DTW uses the steps (1,0), (0,1) and (1,1) from (0, 0) to (n-1, m-1). `dtw` returns the minimum
total cost and the number of steps (matched pairs, i.e. cells) on an optimal warping path; the
project's DTW metric is total / steps (see docs/metrics.md).

Tie-breaking (the step count, hence the metric, depends on it): among the warping paths of
minimum total cost, the one with the fewest steps is chosen. Costs that differ only by the
floating-point rounding of their sums (relative difference <= `TIE_RTOL`) count as equal, so the
choice does not depend on the order in which equal real costs were added. The rule is applied cell
by cell: a cell's accumulated cost is the cheapest predecessor's plus its own point cost, and its
step count one more than the fewest among the predecessors whose cost is within the tolerance of
the cheapest. Because (cost, steps) add up along a path, the total returned is the minimum over
all paths and the step count that of the fewest-steps path among those of that cost (up to
rounding). The result is symmetric: dtw(a, b) == dtw(b, a).

Speed without approximation: cells are swept by anti-diagonals (a cell depends only on the two
previous diagonals, so the loops over a diagonal vectorise), and cells that cannot lie on an
optimal path are skipped. Two cheap warping paths (the staircase along the proportional diagonal
and a greedy walk) give an upper bound U on the DTW total and V on the Fréchet distance. Costs only
grow along a path, so a cell whose accumulated DTW cost exceeds U·(1 + `PRUNE_MARGIN`) is on no
path the rule above can choose (the margin covers rounding and the tie tolerance compounded along
paths of up to `PRUNE_MARGIN / TIE_RTOL` = a million steps), and a cell whose
Fréchet value exceeds V is on no optimal coupling; such cells count as unreachable and each
diagonal is computed only between the first and last reachable cells its predecessors allow. The
results are bit for bit those of the full dynamic program (tests/test_metrics_distances.py).

Empty input, mismatched dimensions, more than 3 coordinates and non-finite coordinates raise
`ValueError`.
"""

from __future__ import annotations

import math
import operator
from typing import NamedTuple

import numpy as np

from decoy_cli.compiled import njit_cached

TIE_RTOL = 1e-12
"""Accumulated DTW costs within this relative difference count as a tie (rounding of the sums)."""

PRUNE_MARGIN = 1e-6
"""Relative slack above the DTW upper bound before a cell is skipped: far above the rounding of a
sum of a few thousand costs and the tie tolerance compounded along a path."""

MAX_DIMS = 3
"""Coordinates per point the kernel handles (positions are at most 3-D)."""

_NO_PATH = np.iinfo(np.int64).max
_EMPTY_LO = np.iinfo(np.int64).max // 2
_EMPTY_HI = -_EMPTY_LO


class CurveDistances(NamedTuple):
    """DTW (total cost, steps on the chosen optimal path) and the discrete Fréchet distance."""

    dtw_total: float
    dtw_steps: int
    frechet: float


@njit_cached(nogil=True)
def _squared(
    a_t: np.ndarray, i: int, b_rev_t: np.ndarray, r: int, frechet_dims: int
) -> tuple[float, float]:
    """Squared distances of a pair of points: over the first `frechet_dims` coordinates, and
    over all three (the arithmetic of `_sweep`, so bounds and sweep agree to the bit)."""
    d0 = a_t[0, i] - b_rev_t[0, r]
    d1 = a_t[1, i] - b_rev_t[1, r]
    d2 = a_t[2, i] - b_rev_t[2, r]
    sq1 = d0 * d0
    sq2 = sq1 + d1 * d1
    sq3 = sq2 + d2 * d2
    return (sq1 if frechet_dims == 1 else (sq2 if frechet_dims == 2 else sq3)), sq3


@njit_cached(nogil=True)
def _upper_bounds(a_t: np.ndarray, b_rev_t: np.ndarray, frechet_dims: int) -> tuple[float, float]:
    """(DTW total, squared Fréchet value), each the smaller over two warping paths (the two
    may come from different paths; each is the value of a real path): the staircase along the
    proportional diagonal and a greedy walk to the cheapest next cell."""
    n = a_t.shape[1]
    m = b_rev_t.shape[1]
    stair_total = 0.0
    stair_worst = 0.0
    j_prev = -1
    for row in range(n):
        j_end = m - 1 if n == 1 else (row * (m - 1) + (n - 1) // 2) // (n - 1)
        j = max(j_prev + 1 if j_end > j_prev else j_prev, 0)
        while j <= j_end:
            sq_f, sq = _squared(a_t, row, b_rev_t, m - 1 - j, frechet_dims)
            stair_total += math.sqrt(sq)
            stair_worst = max(stair_worst, sq_f)
            j += 1
        j_prev = j_end
    i = np.int64(0)  # not a literal 0: `_squared` compiles once for every call
    j = 0
    greedy_worst, sq = _squared(a_t, i, b_rev_t, m - 1, frechet_dims)
    greedy_total = math.sqrt(sq)
    while i < n - 1 or j < m - 1:
        best = math.inf
        best_f = 0.0
        next_i = i
        next_j = j
        if i < n - 1 and j < m - 1:
            best_f, best = _squared(a_t, i + 1, b_rev_t, m - 2 - j, frechet_dims)
            next_i, next_j = i + 1, j + 1
        if i < n - 1:
            sq_f, sq = _squared(a_t, i + 1, b_rev_t, m - 1 - j, frechet_dims)
            if sq < best:
                best, best_f, next_i, next_j = sq, sq_f, i + 1, j
        if j < m - 1:
            sq_f, sq = _squared(a_t, i, b_rev_t, m - 2 - j, frechet_dims)
            if sq < best:
                best, best_f, next_i, next_j = sq, sq_f, i, j + 1
        i = next_i
        j = next_j
        greedy_total += math.sqrt(best)
        greedy_worst = max(greedy_worst, best_f)
    return min(stair_total, greedy_total), min(stair_worst, greedy_worst)


@njit_cached(nogil=True)
def _sweep(
    a_t: np.ndarray,
    b_rev_t: np.ndarray,
    frechet_dims: int,
    rtol: float,
    dtw_limit: float,
    frechet_limit: float,
) -> tuple[float, int, float]:
    """(DTW total, DTW steps, squared Fréchet value) by anti-diagonals, skipping cells above
    the limits (module doc); (inf, 0, inf) when the limits leave no path.

    `a_t` is (3, n); `b_rev_t` is (3, m) with its columns reversed, so cell (i, s - i) of
    diagonal s pairs column i of `a_t` with column i + m - 1 - s of `b_rev_t` and a diagonal is
    a contiguous slice of both. Diagonals are stored by row index i at buffer position i + 1;
    positions outside a diagonal's computed cells hold +inf, so missing predecessors are
    infinitely costly.
    """
    n = a_t.shape[1]
    m = b_rev_t.shape[1]
    inf = math.inf
    cost = np.full((3, n + 2), inf)
    steps = np.zeros((3, n + 2), dtype=np.int64)
    fre = np.full((3, n + 2), inf)
    cost_rows = (cost[0], cost[1], cost[2])
    steps_rows = (steps[0], steps[1], steps[2])
    fre_rows = (fre[0], fre[1], fre[2])
    a0, a1, a2 = a_t[0], a_t[1], a_t[2]
    b0, b1, b2 = b_rev_t[0], b_rev_t[1], b_rev_t[2]
    written_lo = np.zeros(3, dtype=np.int64)  # buffer positions written for each slot
    written_hi = np.full(3, -1, dtype=np.int64)
    p_lo, p_hi = _EMPTY_LO, _EMPTY_HI  # rows reachable on diagonal s - 1
    pp_lo, pp_hi = _EMPTY_LO, _EMPTY_HI  # and on s - 2
    for s in range(n + m - 1):
        if s == 0:
            start, end = 0, 0
        else:
            start = max(min(p_lo, pp_lo + 1), max(0, s - m + 1))
            end = min(max(p_hi + 1, pp_hi + 1), min(s, n - 1))
        if start > end:
            return inf, 0, inf
        slot = s % 3
        c_cost, c_steps, c_fre = cost_rows[slot], steps_rows[slot], fre_rows[slot]
        p_cost, p_steps, p_fre = (
            cost_rows[(s + 2) % 3],
            steps_rows[(s + 2) % 3],
            fre_rows[(s + 2) % 3],
        )
        pp_cost, pp_steps, pp_fre = (
            cost_rows[(s + 1) % 3],
            steps_rows[(s + 1) % 3],
            fre_rows[(s + 1) % 3],
        )
        # Diagonal s - 3 left values in this slot: clear those this diagonal will not overwrite.
        for q in range(written_lo[slot], min(written_hi[slot], start) + 1):
            c_cost[q] = inf
            c_fre[q] = inf
        for q in range(max(written_lo[slot], end + 2), written_hi[slot] + 1):
            c_cost[q] = inf
            c_fre[q] = inf
        written_lo[slot] = start + 1
        written_hi[slot] = end + 1
        offset = m - 1 - s
        count = end - start + 1
        first = s == 0
        # Unsigned indices: numba checks every signed index for Python's negative wraparound,
        # which costs a sixth of the sweep; these are never negative.
        row0 = np.uint64(start)
        col0 = np.uint64(offset + start)
        for t in range(np.uint64(count)):
            row = row0 + t  # row of the cell; its buffer position is row + 1
            col = col0 + t  # column of its partner in b_rev_t
            pos = row + np.uint64(1)
            d0 = a0[row] - b0[col]
            d1 = a1[row] - b1[col]
            d2 = a2[row] - b2[col]
            sq1 = d0 * d0
            sq2 = sq1 + d1 * d1
            sq3 = sq2 + d2 * d2
            here_f = sq1 if frechet_dims == 1 else (sq2 if frechet_dims == 2 else sq3)
            diag_cost = pp_cost[row]
            up_cost = p_cost[row]
            left_cost = p_cost[pos]
            best = min(diag_cost, min(up_cost, left_cost))
            limit = best + rtol * best
            diag_steps = pp_steps[row] if diag_cost <= limit else _NO_PATH
            up_steps = p_steps[row] if up_cost <= limit else _NO_PATH
            left_steps = p_steps[pos] if left_cost <= limit else _NO_PATH
            sel_steps = min(diag_steps, min(up_steps, left_steps))
            if first:
                best = 0.0
                sel_steps = 0
            cell = best + math.sqrt(sq3)
            c_cost[pos] = cell if cell <= dtw_limit else inf
            c_steps[pos] = sel_steps + 1
            cell_f = max(min(pp_fre[row], min(p_fre[row], p_fre[pos])), here_f)
            if first:
                cell_f = here_f
            c_fre[pos] = cell_f if cell_f <= frechet_limit else inf
        lo = start
        while lo <= end and c_cost[lo + 1] == inf and c_fre[lo + 1] == inf:
            lo += 1
        hi = end
        while hi >= lo and c_cost[hi + 1] == inf and c_fre[hi + 1] == inf:
            hi -= 1
        if lo > hi:
            lo, hi = _EMPTY_LO, _EMPTY_HI
        pp_lo, pp_hi = p_lo, p_hi
        p_lo, p_hi = lo, hi
    last = (n + m - 2) % 3
    return cost[last, n], steps[last, n], fre[last, n]


def _as_curves(a: np.ndarray, b: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Validate two curves and return them as float64 (n, d) and (m, d) arrays."""
    a = np.ascontiguousarray(a, dtype=np.float64)  # one compiled layout
    b = np.ascontiguousarray(b, dtype=np.float64)
    if a.ndim != 2 or b.ndim != 2:
        raise ValueError(
            f"curves must be 2-D (points, dims) arrays, got shapes {a.shape} and {b.shape}"
        )
    if a.shape[0] == 0 or b.shape[0] == 0:
        raise ValueError(f"curves must have at least one point, got {a.shape[0]} and {b.shape[0]}")
    if a.shape[1] != b.shape[1] or a.shape[1] == 0:
        raise ValueError(f"curves must share a dimension >= 1, got {a.shape[1]} and {b.shape[1]}")
    if a.shape[1] > MAX_DIMS:
        raise ValueError(f"curves must have at most {MAX_DIMS} coordinates, got {a.shape[1]}")
    if not (np.isfinite(a).all() and np.isfinite(b).all()):
        raise ValueError("curves must not contain NaN or infinite coordinates")
    return a, b


@njit_cached(nogil=True)
def curve_kernel(
    a: np.ndarray, b: np.ndarray, frechet_dims: int, prune: bool = True
) -> tuple[float, int, float]:
    """(DTW total, DTW steps, Fréchet distance) of curves already validated by `_as_curves`.

    Pads to 3 coordinates (zero coordinates add exactly nothing), bounds and sweeps; with
    `prune` off the sweep computes every cell (the tests compare the two). The bounds are the
    values of real paths computed with the sweep's arithmetic, so they never cut off the last
    cell. For callers in this package that validated their curves once (the trajectory metrics).
    """
    n, d = a.shape
    m = b.shape[0]
    a_t = np.zeros((MAX_DIMS, n))
    b_rev_t = np.zeros((MAX_DIMS, m))
    for k in range(d):
        for i in range(n):
            a_t[k, i] = a[i, k]
        for j in range(m):
            b_rev_t[k, m - 1 - j] = b[j, k]
    dtw_limit = frechet_limit = math.inf
    if prune:
        total_bound, frechet_limit = _upper_bounds(a_t, b_rev_t, frechet_dims)
        dtw_limit = total_bound + total_bound * PRUNE_MARGIN
    total, steps, frechet_sq = _sweep(
        a_t, b_rev_t, frechet_dims, TIE_RTOL, dtw_limit, frechet_limit
    )
    return total, steps, math.sqrt(frechet_sq)


def dtw_and_frechet(
    a: np.ndarray, b: np.ndarray, frechet_dims: int | None = None
) -> CurveDistances:
    """Exact DTW of two curves and their exact discrete Fréchet distance, in one sweep.

    The Fréchet distance is over the first `frechet_dims` coordinates (default: all of them),
    e.g. 2 for the x-y projection of 3-D positions.
    """
    a, b = _as_curves(a, b)
    dims = a.shape[1] if frechet_dims is None else operator.index(frechet_dims)
    if isinstance(frechet_dims, bool) or not 1 <= dims <= a.shape[1]:
        raise ValueError(f"frechet_dims must be between 1 and {a.shape[1]}, got {dims}")
    return CurveDistances(*curve_kernel(a, b, dims))


def dtw(a: np.ndarray, b: np.ndarray) -> tuple[float, int]:
    """Exact DTW of two curves: (minimum total cost, steps on the chosen optimal warping path).

    Point cost is the Euclidean distance; steps (1,0), (0,1), (1,1); ties as in the module doc.
    The mean cost per matched pair (the project's `dtw` metric) is `total / steps`.
    """
    a, b = _as_curves(a, b)
    total, steps, _ = curve_kernel(a, b, a.shape[1])
    return total, steps


def dtw_mean(a: np.ndarray, b: np.ndarray) -> float:
    """DTW total cost divided by the number of steps on the optimal warping path."""
    total, steps = dtw(a, b)
    return total / steps


def frechet(a: np.ndarray, b: np.ndarray) -> float:
    """Exact discrete Fréchet distance of two curves (Euclidean point distance)."""
    a, b = _as_curves(a, b)
    return curve_kernel(a, b, a.shape[1])[2]
