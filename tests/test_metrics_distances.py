"""DTW and discrete Fréchet kernels against hand-checked cases and independent oracles.

Oracles: `similaritymeasures` (exact, slow) for the DTW total cost and the Fréchet distance, and,
for the warping-path length, a brute-force enumeration of all warping paths and a plain-python
lexicographic DP written here.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterator
from fractions import Fraction

import numpy as np
import pytest
import similaritymeasures

from decoy_cli.metrics import dtw, dtw_and_frechet, dtw_mean, frechet
from decoy_cli.metrics.distances import (
    PRUNE_MARGIN,
    TIE_RTOL,
    _sweep,
    _upper_bounds,
    curve_kernel,
)

STEPS = ((1, 0), (0, 1), (1, 1))


def col(*values: float) -> np.ndarray:
    """A 1-D curve as an (n, 1) array."""
    return np.array(values, dtype=np.float64)[:, None]


def warping_paths(n: int, m: int) -> Iterator[list[tuple[int, int]]]:
    """Every warping path from (0, 0) to (n-1, m-1) with steps (1,0), (0,1), (1,1)."""

    def extend(path: list[tuple[int, int]]) -> Iterator[list[tuple[int, int]]]:
        i, j = path[-1]
        if (i, j) == (n - 1, m - 1):
            yield path
            return
        for di, dj in STEPS:
            if i + di < n and j + dj < m:
                yield from extend([*path, (i + di, j + dj)])

    yield from extend([(0, 0)])


def brute_force_dtw(a: np.ndarray, b: np.ndarray, rtol: float = 1e-12) -> tuple[float, int]:
    """(min total cost, fewest steps among paths within rtol of it) by enumerating all paths."""
    dist = np.linalg.norm(a[:, None, :] - b[None, :, :], axis=2)
    scored = [
        (math.fsum(dist[i, j] for i, j in path), len(path))
        for path in warping_paths(len(a), len(b))
    ]
    best = min(cost for cost, _ in scored)
    return best, min(steps for cost, steps in scored if cost <= best * (1 + rtol))


def exact_decimal_dtw(a: list[str], b: list[str]) -> tuple[Fraction, int]:
    """Lexicographic (cost, steps) minimum over all paths of 1-D decimal curves, exact rationals."""
    fa = [Fraction(v) for v in a]
    fb = [Fraction(v) for v in b]
    return min(
        (sum((abs(fa[i] - fb[j]) for i, j in path), Fraction(0)), len(path))
        for path in warping_paths(len(a), len(b))
    )


def python_dp_dtw(a: list[int], b: list[int]) -> tuple[int, int]:
    """Plain-python full-matrix DP of the lexicographic (cost, steps) minimum, integer 1-D data."""
    n, m = len(a), len(b)
    best: list[list[tuple[int, int]]] = [[(0, 0)] * m for _ in range(n)]
    for i in range(n):
        for j in range(m):
            c = abs(a[i] - b[j])
            preds = [best[i - di][j - dj] for di, dj in STEPS if i >= di and j >= dj]
            if not preds:
                best[i][j] = (c, 1)
            else:
                cost, steps = min(preds)
                best[i][j] = (cost + c, steps + 1)
    return best[n - 1][m - 1]


# ---- hand-checked cases ----------------------------------------------------------------------


def test_dtw_hand_case_unequal_lengths() -> None:
    # a = 0, 1, 2 against b = 0, 2 (1-D). Costs |a_i - b_j|:
    #   a0: 0 2 / a1: 1 1 / a2: 2 0. Best paths (0,0)(1,0)(2,1) and (0,0)(1,1)(2,1) cost
    #   0 + 1 + 0 = 1 with 3 steps; every other path costs >= 2.
    assert dtw(col(0, 1, 2), col(0, 2)) == (1.0, 3)
    assert dtw_mean(col(0, 1, 2), col(0, 2)) == pytest.approx(1 / 3, rel=1e-15)


def test_dtw_equal_cost_paths_take_the_fewest_steps() -> None:
    # a = 0, 2 against b = 1, 0. Costs: c00 = 1, c01 = 0, c10 = 1, c11 = 2.
    #   diagonal (0,0)(1,1): 1 + 2 = 3, 2 steps; detour (0,0)(0,1)(1,1): 1 + 0 + 2 = 3, 3 steps;
    #   (0,0)(1,0)(1,1): 4. Tie at cost 3 -> the 2-step path: mean 1.5, not 1.0.
    assert dtw(col(0, 2), col(1, 0)) == (3.0, 2)
    assert dtw(col(1, 0), col(0, 2)) == (3.0, 2)


def test_dtw_time_shift_hand_case() -> None:
    # b is a delayed by one frame: a = 0..4, b = 0, 0, 1, 2, 3. Zero-cost cells are (0,0),
    #   (0,1), (1,2), (2,3), (3,4); the end cell (4,4) costs 1 and lies on every path, so the
    #   optimum is the zero chain plus (4,4): cost 1, 6 steps (the diagonal costs 4).
    assert dtw(col(0, 1, 2, 3, 4), col(0, 0, 1, 2, 3)) == (1.0, 6)


def test_dtw_single_points_and_one_against_many() -> None:
    assert dtw(np.array([[0.0, 0.0, 0.0]]), np.array([[3.0, 4.0, 0.0]])) == (5.0, 1)
    # One point at 0 against 1, 2, 3: the only path visits every cell: 1 + 2 + 3 = 6, 3 steps.
    assert dtw(col(0), col(1, 2, 3)) == (6.0, 3)
    assert dtw(col(1, 2, 3), col(0)) == (6.0, 3)


def test_dtw_ties_broken_on_real_costs_not_on_rounding() -> None:
    # In exact arithmetic the cheapest paths cost 0.8 and the shortest of them has 4 steps; in
    # float64 a 5-step path of the same real cost sums to a smaller value by rounding. The tie
    # tolerance makes the kernel pick the 4-step path, as the exact oracle does.
    a, b = ["0.3", "0.1", "0.3"], ["0.1", "0.2", "0.6", "0.1"]
    assert exact_decimal_dtw(a, b) == (Fraction(4, 5), 4)
    total, steps = dtw(col(*map(float, a)), col(*map(float, b)))
    assert steps == 4
    assert total == pytest.approx(0.8, rel=1e-12)


def test_frechet_hand_cases() -> None:
    # a = (0,0), (1,0), (2,0); b = (0,1), (2,1). Distances: a0-b0 1, a0-b1 √5, a1-b0 √2,
    #   a1-b1 √2, a2-b0 √5, a2-b1 1. Every coupling passes a1 (√2 to either b point) and the
    #   coupling a0-b0, a1-b0 or a1-b1, a2-b1 avoids √5, so the distance is √2.
    a = np.array([[0.0, 0.0], [1.0, 0.0], [2.0, 0.0]])
    b = np.array([[0.0, 1.0], [2.0, 1.0]])
    assert frechet(a, b) == pytest.approx(math.sqrt(2), rel=1e-15)
    # One point against several: the coupling must use every pair, so the largest distance.
    assert frechet(col(0), col(1, -3, 2)) == 3.0
    assert frechet(np.array([[1.0, 2.0, 3.0]]), np.array([[1.0, 2.0, 3.0]])) == 0.0


def test_identical_curves_cost_nothing() -> None:
    rng = np.random.default_rng(1)
    a = rng.normal(size=(40, 3))
    assert dtw(a, a) == (0.0, 40)
    assert frechet(a, a) == 0.0


# ---- independent oracles -------------------------------------------------------------------

LENGTHS = [(1, 1), (1, 7), (9, 1), (2, 2), (3, 8), (17, 5), (30, 31), (64, 40), (120, 77)]


@pytest.mark.parametrize("dim", [1, 2, 3])
@pytest.mark.parametrize(("n", "m"), LENGTHS)
def test_against_similaritymeasures(n: int, m: int, dim: int) -> None:
    rng = np.random.default_rng(1000 * n + 10 * m + dim)
    a = rng.normal(scale=5.0, size=(n, dim))
    b = rng.normal(scale=5.0, size=(m, dim)) + 1.0
    total, steps = dtw(a, b)
    assert total == pytest.approx(similaritymeasures.dtw(a, b)[0], rel=1e-9)
    assert max(n, m) <= steps <= n + m - 1
    assert frechet(a, b) == pytest.approx(similaritymeasures.frechet_dist(a, b), rel=1e-9)


def test_against_similaritymeasures_full_size() -> None:
    rng = np.random.default_rng(7)
    a = np.cumsum(rng.normal(size=(310, 3)), axis=0)
    b = np.cumsum(rng.normal(size=(290, 3)), axis=0)
    assert dtw(a, b)[0] == pytest.approx(similaritymeasures.dtw(a, b)[0], rel=1e-9)
    assert frechet(a, b) == pytest.approx(similaritymeasures.frechet_dist(a, b), rel=1e-9)


def test_steps_match_brute_force_on_random_curves() -> None:
    rng = np.random.default_rng(2)
    for _ in range(150):
        n, m = rng.integers(1, 6, size=2)
        dim = int(rng.integers(1, 4))
        a = rng.normal(size=(n, dim))
        b = rng.normal(size=(m, dim))
        expected_total, expected_steps = brute_force_dtw(a, b)
        total, steps = dtw(a, b)
        assert steps == expected_steps
        assert total == pytest.approx(expected_total, rel=1e-12)


def test_steps_match_exact_oracle_on_tie_rich_decimal_curves() -> None:
    # Few distinct decimal values make many equal-cost paths of different lengths, some of them
    # unequal after float rounding; the exact rational oracle defines the expected step count.
    rng = np.random.default_rng(3)
    values = ["0", "0.1", "0.2", "0.3", "0.6", "0.7", "1.1"]
    for _ in range(250):
        n, m = rng.integers(1, 6, size=2)
        a = list(rng.choice(values, size=n))
        b = list(rng.choice(values, size=m))
        expected_total, expected_steps = exact_decimal_dtw(a, b)
        total, steps = dtw(col(*map(float, a)), col(*map(float, b)))
        assert steps == expected_steps, (a, b)
        assert total == pytest.approx(float(expected_total), rel=1e-12, abs=1e-15)


def test_steps_match_python_dp_on_integer_curves() -> None:
    # Integer coordinates give exact float costs, so exact tuple comparison is the reference.
    rng = np.random.default_rng(4)
    for n, m in [(20, 30), (31, 12), (45, 45), (1, 25), (60, 3)]:
        a = [int(v) for v in rng.integers(0, 4, size=n)]
        b = [int(v) for v in rng.integers(0, 4, size=m)]
        expected = python_dp_dtw(a, b)
        # Embed the 1-D values on the slanted 3-D line t·(3, 4, 12): distances are 13·|Δt|.
        direction = np.array([3.0, 4.0, 12.0])
        result = dtw(np.outer(a, direction), np.outer(b, direction))
        assert result[1] == expected[1]
        assert result[0] == pytest.approx(13.0 * expected[0], rel=1e-12)


def test_symmetric_in_its_arguments() -> None:
    rng = np.random.default_rng(5)
    for n, m in [(1, 4), (13, 21), (50, 8)]:
        a = rng.normal(size=(n, 3))
        b = rng.normal(size=(m, 3))
        assert dtw(a, b) == dtw(b, a)
        assert frechet(a, b) == frechet(b, a)


# ---- bad input -----------------------------------------------------------------------------


@pytest.mark.parametrize("kernel", [dtw, frechet])
def test_bad_input_raises_value_error(kernel: Callable[[np.ndarray, np.ndarray], object]) -> None:
    good = np.zeros((3, 3))
    with pytest.raises(ValueError, match="at least one point"):
        kernel(np.zeros((0, 3)), good)
    with pytest.raises(ValueError, match="at least one point"):
        kernel(good, np.zeros((0, 3)))
    with pytest.raises(ValueError, match="share a dimension"):
        kernel(good, np.zeros((3, 2)))
    with pytest.raises(ValueError, match="2-D"):
        kernel(np.zeros(3), good)
    with pytest.raises(ValueError, match="NaN or infinite"):
        kernel(good, np.array([[0.0, np.nan, 0.0]]))


# ---- pruning and the fused kernel ----------------------------------------------------------


def pruning_cases() -> Iterator[tuple[np.ndarray, np.ndarray]]:
    """Curves where the pruning bound is tight (near copies), loose (unrelated walks) and full of
    exact ties (integer grids, standing still), of equal and different lengths and dimensions."""
    rng = np.random.default_rng(11)
    for _ in range(60):
        n, m = (int(v) for v in rng.integers(1, 90, size=2))
        dim = int(rng.integers(1, 4))
        walk = np.cumsum(rng.normal(size=(max(n, m), dim)), axis=0)
        yield walk[:n], walk[:m] + rng.normal(scale=0.2, size=(m, dim))
        yield walk[:n], np.cumsum(rng.normal(size=(m, dim)), axis=0)
        yield (
            rng.integers(0, 3, size=(n, dim)).astype(float),
            rng.integers(0, 3, size=(m, dim)).astype(float),
        )
        still = np.repeat(walk[: max(n // 4, 1)], 4, axis=0)[:n]
        yield still, walk[:m]


def padded(a: np.ndarray, b: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The kernel's layout: (3, n) and (3, m) with b's points reversed, zero-padded."""
    a_t = np.zeros((3, len(a)))
    a_t[: a.shape[1]] = a.T
    b_rev_t = np.zeros((3, len(b)))
    b_rev_t[: b.shape[1]] = b[::-1].T
    return a_t, b_rev_t


def test_the_bounded_sweep_is_the_full_sweep() -> None:
    for a, b in pruning_cases():
        a_t, b_rev_t = padded(a, b)
        for dims in range(1, a.shape[1] + 1):
            total_bound, frechet_bound = _upper_bounds(a_t, b_rev_t, dims)
            limit = total_bound * (1 + PRUNE_MARGIN)
            pruned = _sweep(a_t, b_rev_t, dims, TIE_RTOL, limit, frechet_bound)
            full = _sweep(a_t, b_rev_t, dims, TIE_RTOL, math.inf, math.inf)
            assert math.isfinite(pruned[0]) and math.isfinite(pruned[2])
            assert pruned == full
            assert curve_kernel(a, b, dims, True) == curve_kernel(a, b, dims, False)


def test_the_sweep_skips_what_lies_above_its_limits() -> None:
    # Limits just below the optimum leave no path: the sweep really drops those cells.
    rng = np.random.default_rng(13)
    a = np.cumsum(rng.normal(size=(40, 3)), axis=0)
    b = a + rng.normal(scale=0.3, size=a.shape)
    a_t, b_rev_t = padded(a, b)
    total, _, frechet_sq = _sweep(a_t, b_rev_t, 3, TIE_RTOL, math.inf, math.inf)
    assert _sweep(a_t, b_rev_t, 3, TIE_RTOL, total * 0.999, math.inf)[0] == math.inf
    assert _sweep(a_t, b_rev_t, 3, TIE_RTOL, math.inf, frechet_sq * 0.999)[2] == math.inf


def test_dtw_and_frechet_is_dtw_and_frechet_of_the_first_coordinates() -> None:
    rng = np.random.default_rng(12)
    a = np.cumsum(rng.normal(size=(70, 3)), axis=0)
    b = np.cumsum(rng.normal(size=(55, 3)), axis=0)
    both = dtw_and_frechet(a, b, frechet_dims=2)
    assert (both.dtw_total, both.dtw_steps) == dtw(a, b)
    assert both.frechet == frechet(a[:, :2], b[:, :2])
    assert dtw_and_frechet(a, b).frechet == frechet(a, b)
    with pytest.raises(ValueError, match="frechet_dims"):
        dtw_and_frechet(a, b, frechet_dims=4)
    with pytest.raises(ValueError, match="frechet_dims"):
        dtw_and_frechet(a, b, frechet_dims=True)
    with pytest.raises(TypeError):
        dtw_and_frechet(a, b, frechet_dims=2.5)  # type: ignore[arg-type]


def test_more_than_three_coordinates_are_refused() -> None:
    with pytest.raises(ValueError, match="at most 3 coordinates"):
        dtw(np.zeros((3, 4)), np.zeros((3, 4)))
