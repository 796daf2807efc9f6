"""`paper_dtw_fastdtw`: the paper's FastDTW beside the exact DTW of the paper protocol."""

from __future__ import annotations

import math

import numpy as np
from fastdtw import fastdtw
from scipy.spatial.distance import euclidean

from decoy_cli.metrics import FASTDTW_METRIC, dtw, resample, trajectory_metrics
from decoy_cli.metrics.fastdtw_metric import fastdtw_mean


def test_fastdtw_never_costs_less_than_the_exact_dtw() -> None:
    rng = np.random.default_rng(31)
    for _ in range(40):
        n, m = (int(v) for v in rng.integers(5, 120, size=2))
        a = np.cumsum(rng.normal(size=(n, 3)), axis=0)
        b = np.cumsum(rng.normal(size=(m, 3)), axis=0)
        fast_total, path = fastdtw(a, b, radius=1, dist=euclidean)
        exact_total, _ = dtw(a, b)
        assert fast_total >= exact_total * (1 - 1e-12)
        assert fastdtw_mean(a, b) == fast_total / len(path)


def test_on_curves_fastdtw_solves_exactly_it_agrees_with_the_exact_dtw() -> None:
    # FastDTW runs the full DTW on curves of at most radius + 2 points.
    a = np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [2.0, 0.5, 0.0]])
    b = np.array([[0.0, 1.0, 0.0], [2.0, 1.0, 0.0]])
    total, steps = dtw(a, b)
    assert math.isclose(fastdtw_mean(a, b), total / steps, rel_tol=1e-12)
    assert fastdtw_mean(a, a) == 0.0


def test_trajectory_metrics_add_it_on_request() -> None:
    rng = np.random.default_rng(32)
    original = np.cumsum(rng.normal(size=(80, 3)), axis=0)
    simulated = original + rng.normal(scale=0.5, size=original.shape)
    alive = np.ones(80, dtype=bool)
    plain = trajectory_metrics(original, alive, simulated, alive)
    assert FASTDTW_METRIC not in plain.values
    both = trajectory_metrics(original, alive, simulated, alive, fastdtw=True)
    expected = fastdtw_mean(resample(original), resample(simulated))
    assert both.values[FASTDTW_METRIC] == expected
    assert {k: v for k, v in both.values.items() if k != FASTDTW_METRIC} == plain.values
    dead = np.zeros(80, dtype=bool)
    missing = trajectory_metrics(original, dead, simulated, alive, fastdtw=True)
    assert missing.reason and math.isnan(missing.values[FASTDTW_METRIC])
