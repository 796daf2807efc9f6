"""Trajectory metrics of both protocols on hand-checked and oracle-checked player-rounds."""

from __future__ import annotations

import math

import numpy as np
import pandas as pd
import pytest
import similaritymeasures

from decoy_cli.metrics import (
    METRIC_NAMES,
    METRIC_NAMES_CLOCK,
    METRIC_NAMES_PAPER,
    PAPER_LENGTH,
    PlayerRound,
    resample,
    trajectory_metrics,
    trajectory_metrics_frame,
)
from decoy_cli.metrics.trajectory_kernel import pairwise_sum


def line(frames: int) -> np.ndarray:
    """A player walking 1 m per frame along +x."""
    return np.c_[np.arange(frames, dtype=np.float64), np.zeros(frames), np.zeros(frames)]


def alive(frames: int, first: int = 0, last: int | None = None) -> np.ndarray:
    mask = np.zeros(frames, dtype=bool)
    mask[first : frames if last is None else last + 1] = True
    return mask


def assert_dtw_mean_matches_oracle(mean: float, a: np.ndarray, b: np.ndarray) -> None:
    """The oracle's total cost divided by `mean` is a warping-path length (an integer in range)."""
    steps = similaritymeasures.dtw(a, b)[0] / mean
    assert steps == pytest.approx(round(steps), abs=1e-6)
    assert max(len(a), len(b)) <= round(steps) <= len(a) + len(b) - 1


def test_metric_names_follow_the_docs() -> None:
    assert METRIC_NAMES_CLOCK == (
        "mean_dist",
        "rmse",
        "max_dist",
        "dtw",
        "frechet_2d",
        "final_dist",
    )
    assert METRIC_NAMES_PAPER == ("paper_euclidean", "paper_rmse", "paper_dtw", "paper_frechet_2d")
    assert METRIC_NAMES == METRIC_NAMES_CLOCK + METRIC_NAMES_PAPER
    assert PAPER_LENGTH == 451


def test_constant_offset_hand_case() -> None:
    # S = O + (0, 3, 4): every frame is 5 m off. DTW: d(O_i, S_j) = sqrt((i-j)² + 25) >= 5 with
    #   equality on the diagonal only, so the diagonal is optimal: 5 per pair. The x-y offset is
    #   3, so Fréchet 2-D is 3. Resampled, the offset is unchanged: ‖A − B‖_F = 5·sqrt(L), so
    #   paper_euclidean = 5/sqrt(451); per coordinate the squares are 0, 9, 16: paper_rmse =
    #   sqrt(25/3).
    o = line(12)
    s = o + np.array([0.0, 3.0, 4.0])
    result = trajectory_metrics(o, alive(12), s, alive(12))
    assert result.reason is None
    expected = {
        "mean_dist": 5.0,
        "rmse": 5.0,
        "max_dist": 5.0,
        "dtw": 5.0,
        "frechet_2d": 3.0,
        "final_dist": 5.0,
        "paper_euclidean": 5.0 / math.sqrt(451),
        "paper_rmse": math.sqrt(25.0 / 3.0),
        "paper_dtw": 5.0,
        "paper_frechet_2d": 3.0,
    }
    assert list(result.values) == list(METRIC_NAMES)
    for name, value in expected.items():
        assert result.values[name] == pytest.approx(value, rel=1e-12), name


def test_time_shift_penalised_on_the_clock_not_by_dtw() -> None:
    # S lags O by one frame: O_x = 0..4, S_x = 0, 0, 1, 2, 3. Clock distances 0, 1, 1, 1, 1:
    #   mean 0.8, rmse sqrt(4/5), max 1, final 1. DTW: zero-cost chain then the end pair (4 vs 3):
    #   total 1 over 6 steps = 1/6. Fréchet: every coupling holds the end pair, distance 1.
    o = line(5)
    s = o.copy()
    s[:, 0] = [0, 0, 1, 2, 3]
    values = trajectory_metrics(o, alive(5), s, alive(5)).values
    assert values["mean_dist"] == pytest.approx(0.8, rel=1e-12)
    assert values["rmse"] == pytest.approx(math.sqrt(0.8), rel=1e-12)
    assert values["max_dist"] == 1.0
    assert values["final_dist"] == 1.0
    assert values["dtw"] == pytest.approx(1 / 6, rel=1e-12)
    assert values["frechet_2d"] == 1.0


def test_alive_masks_select_frames() -> None:
    # 8 frames; original alive 0..5, simulated alive 0..3, so k = 0..3. S_t = O_t + (0, 0, t):
    #   clock distances 0, 1, 2, 3 -> mean 1.5, rmse sqrt(14/4), max 3, final (frame 3) 3.
    #   Positions at dead frames are garbage (NaN, far away) and must not matter.
    frames = 8
    o = line(frames)
    s = o + np.c_[np.zeros(frames), np.zeros(frames), np.arange(frames)]
    o[6:] = np.nan
    s[4:] = 1e6
    o_alive, s_alive = alive(frames, 0, 5), alive(frames, 0, 3)
    result = trajectory_metrics(o, o_alive, s, s_alive)
    assert result.reason is None
    values = result.values
    assert values["mean_dist"] == pytest.approx(1.5, rel=1e-12)
    assert values["rmse"] == pytest.approx(math.sqrt(3.5), rel=1e-12)
    assert values["max_dist"] == 3.0
    assert values["final_dist"] == 3.0
    # DTW and Fréchet use all alive frames of each (6 and 4 points): check with the oracle.
    o_live, s_live = o[o_alive], s[s_alive]
    assert_dtw_mean_matches_oracle(values["dtw"], o_live, s_live)
    assert values["frechet_2d"] == pytest.approx(
        similaritymeasures.frechet_dist(o_live[:, :2], s_live[:, :2]), rel=1e-9
    )


def test_paper_protocol_against_independent_computation() -> None:
    rng = np.random.default_rng(11)
    frames = 240
    o = np.cumsum(rng.normal(scale=0.5, size=(frames, 3)), axis=0)
    s = o + np.cumsum(rng.normal(scale=0.2, size=(frames, 3)), axis=0)
    o_alive, s_alive = alive(frames, 0, 199), alive(frames, 0, 229)
    values = trajectory_metrics(o, o_alive, s, s_alive).values

    def interp(points: np.ndarray) -> np.ndarray:
        x = np.linspace(0.0, 1.0, points.shape[0])
        q = np.linspace(0.0, 1.0, PAPER_LENGTH)
        return np.column_stack([np.interp(q, x, points[:, c]) for c in range(3)])

    a, b = interp(o[o_alive]), interp(s[s_alive])
    per_point = np.linalg.norm(a - b, axis=1)
    # paper_euclidean is the RMS point distance divided by sqrt(L), paper_rmse is per coordinate.
    assert values["paper_euclidean"] == pytest.approx(
        np.sqrt(np.mean(per_point**2)) / np.sqrt(PAPER_LENGTH), rel=1e-9
    )
    assert values["paper_rmse"] == pytest.approx(np.sqrt(np.mean(per_point**2) / 3), rel=1e-9)
    assert values["paper_frechet_2d"] == pytest.approx(
        similaritymeasures.frechet_dist(a[:, :2], b[:, :2]), rel=1e-9
    )
    assert_dtw_mean_matches_oracle(values["paper_dtw"], a, b)
    k = o_alive & s_alive
    dist = np.linalg.norm(o[k] - s[k], axis=1)
    assert values["mean_dist"] == pytest.approx(dist.mean(), rel=1e-12)
    assert values["final_dist"] == pytest.approx(dist[-1], rel=1e-12)
    assert values["frechet_2d"] == pytest.approx(
        similaritymeasures.frechet_dist(o[o_alive][:, :2], s[s_alive][:, :2]), rel=1e-9
    )


def test_resample_is_linear_over_normalised_index() -> None:
    points = np.array([[0.0, 0.0, 0.0], [10.0, 0.0, 2.0], [10.0, 5.0, 2.0]])
    out = resample(points, 5)
    # Fractional indices 0, 0.5, 1, 1.5, 2.
    np.testing.assert_allclose(
        out, [[0, 0, 0], [5, 0, 1], [10, 0, 2], [10, 2.5, 2], [10, 5, 2]], rtol=0, atol=1e-12
    )
    full = resample(points)
    assert full.shape == (PAPER_LENGTH, 3)
    assert np.array_equal(full[0], points[0]) and np.array_equal(full[-1], points[-1])
    with pytest.raises(ValueError, match="at least 2"):
        resample(points[:1])


@pytest.mark.parametrize(
    ("o_alive", "s_alive", "reason"),
    [
        (alive(6, 0, 0), alive(6), "original alive in fewer than 2 frames"),
        (alive(6), alive(6, 2, 2), "simulated alive in fewer than 2 frames"),
        (alive(6), np.zeros(6, dtype=bool), "simulated alive in fewer than 2 frames"),
        (alive(6, 0, 2), alive(6, 3, 5), "no frame alive in both"),
    ],
)
def test_not_evaluable_gives_nan_and_reason(
    o_alive: np.ndarray, s_alive: np.ndarray, reason: str
) -> None:
    result = trajectory_metrics(line(6), o_alive, line(6) + 1.0, s_alive)
    assert result.reason == reason
    assert list(result.values) == list(METRIC_NAMES)
    assert all(math.isnan(v) for v in result.values.values())


def test_non_finite_position_at_alive_frame_is_a_reason() -> None:
    s = line(6)
    s[2, 1] = np.inf
    result = trajectory_metrics(line(6), alive(6), s, alive(6))
    assert result.reason == "non-finite position at an alive frame"
    assert all(math.isnan(v) for v in result.values.values())


def test_malformed_arrays_raise() -> None:
    with pytest.raises(ValueError, match="same frame clock"):
        trajectory_metrics(line(6), alive(6), line(5), alive(5))
    with pytest.raises(ValueError, match="same frame clock"):
        trajectory_metrics(line(6)[:, :2], alive(6), line(6)[:, :2], alive(6))
    with pytest.raises(ValueError, match="boolean"):
        trajectory_metrics(line(6), np.ones(6), line(6), alive(6))
    with pytest.raises(ValueError, match="boolean"):
        trajectory_metrics(line(6), alive(6), line(6), alive(5))


def test_frame_of_many_player_rounds() -> None:
    rounds = [
        PlayerRound(
            {"round": 1, "player": "a", "side": "T"}, line(6), alive(6), line(6) + 1.0, alive(6)
        ),
        PlayerRound(
            {"round": 1, "player": "b", "side": "CT"}, line(6), alive(6, 0, 0), line(6), alive(6)
        ),
    ]
    frame = trajectory_metrics_frame(rounds)
    assert list(frame.columns) == ["round", "player", "side", *METRIC_NAMES, "reason"]
    assert len(frame) == 2
    assert pd.isna(frame.loc[0, "reason"])
    assert frame.loc[0, "mean_dist"] == pytest.approx(math.sqrt(3), rel=1e-12)
    assert frame.loc[1, "reason"] == "original alive in fewer than 2 frames"
    assert frame.loc[1, list(METRIC_NAMES)].isna().all()

    empty = trajectory_metrics_frame([])
    assert isinstance(empty, pd.DataFrame) and empty.empty
    assert list(empty.columns) == [*METRIC_NAMES, "reason"]

    mixed = [rounds[0], PlayerRound({"round": 2}, line(6), alive(6), line(6), alive(6))]
    with pytest.raises(ValueError, match="keys differ"):
        trajectory_metrics_frame(mixed)
    with pytest.raises(ValueError, match="reserved"):
        trajectory_metrics_frame([PlayerRound({"dtw": 1}, line(6), alive(6), line(6), alive(6))])


# ---- the compiled core against plain numpy -------------------------------------------------


def test_resampling_refuses_what_is_not_a_polyline() -> None:
    with pytest.raises(ValueError, match=r"\(n, d\) array"):
        resample(np.arange(5.0))
    with pytest.raises(ValueError, match="at least 2"):
        resample(np.zeros((1, 3)))


def test_pairwise_sum_is_numpys_sum_to_the_bit() -> None:
    rng = np.random.default_rng(21)
    for n in [*range(0, 40), 127, 128, 129, 255, 256, 257, 1000, 1353, 4099]:
        values = rng.normal(scale=1e3, size=n) ** 2
        assert pairwise_sum(values) == np.sum(values), n


def test_resampling_is_numpys_linspace_interpolation_to_the_bit() -> None:
    rng = np.random.default_rng(22)
    for n in [2, 3, 7, 150, 451, 452, 999]:
        points = np.cumsum(rng.normal(size=(n, 3)), axis=0)
        position = np.linspace(0.0, n - 1.0, PAPER_LENGTH)
        lower = np.minimum(position.astype(np.int64), n - 2)
        frac = (position - lower)[:, None]
        expected = points[lower] * (1.0 - frac) + points[lower + 1] * frac
        assert np.array_equal(resample(points), expected), n


def test_metrics_equal_the_plain_numpy_definitions() -> None:
    rng = np.random.default_rng(23)
    for _ in range(30):
        frames = int(rng.integers(5, 300))
        original = np.cumsum(rng.normal(size=(frames, 3)), axis=0)
        simulated = original + np.cumsum(rng.normal(scale=0.3, size=(frames, 3)), axis=0)
        original_alive = alive(frames, last=int(rng.integers(2, frames)))
        simulated_alive = alive(frames, first=int(rng.integers(0, 2)))
        simulated_alive[rng.integers(0, frames, size=frames // 10)] = False  # gaps mid-round
        values = trajectory_metrics(original, original_alive, simulated, simulated_alive).values
        both = original_alive & simulated_alive
        step = np.linalg.norm(original[both] - simulated[both], axis=1)
        a = resample(original[original_alive])
        b = resample(simulated[simulated_alive])
        assert values["mean_dist"] == step.mean()
        assert values["rmse"] == np.sqrt(np.mean(step**2))
        assert values["max_dist"] == step.max()
        assert values["final_dist"] == step[-1]
        assert values["paper_rmse"] == np.sqrt(np.mean((a - b) ** 2))
        # numpy's norm sums with BLAS, the kernel pairwise: equal to rounding
        assert values["paper_euclidean"] == pytest.approx(
            np.linalg.norm(a - b) / PAPER_LENGTH, rel=1e-14
        )
