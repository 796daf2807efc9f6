"""DIP calibration: the measures on hand cases, and recalibration of a miscalibrated model."""

from __future__ import annotations

import numpy as np
import pytest

from decoy_cli.damage.calibration import Calibration
from decoy_cli.modeling.calibration_fit import (
    brier_score,
    ece_floor,
    expected_calibration_error,
    fit_calibration,
    reliability_curve,
)
from decoy_cli.modeling.scores import roc_auc


def test_measures_on_hand_cases() -> None:
    labels = np.array([True, False, True, False])
    assert brier_score(labels, np.array([1.0, 0.0, 1.0, 0.0])) == 0.0
    assert brier_score(labels, np.full(4, 0.5)) == 0.25
    # all in the 0.5 bin: half hit, mean 0.5 -> no gap
    assert expected_calibration_error(labels, np.full(4, 0.5)) == 0.0
    # said 0.9 for all, half hit: gap 0.4
    assert expected_calibration_error(labels, np.full(4, 0.9)) == pytest.approx(0.4)
    (row,) = reliability_curve(labels, np.full(4, 0.9))
    assert (row["count"], row["hit_share"], row["low"]) == (4, 0.5, 0.9)
    with pytest.raises(ValueError, match="within"):
        brier_score(labels, np.array([1.2, 0.0, 0.0, 0.0]))


def test_the_ece_floor_is_what_calibrated_labels_score() -> None:
    rng = np.random.default_rng(3)
    p = rng.uniform(0.05, 0.6, 234)  # the size of the real test part
    by_hand = np.mean([expected_calibration_error(rng.random(234) < p, p) for _ in range(400)])
    assert ece_floor(p) == pytest.approx(by_hand, rel=0.1)
    assert 0.03 < ece_floor(p) < 0.08  # a few hundred samples cannot show an ECE of 0
    assert ece_floor(np.tile(p, 100)) < ece_floor(p) / 5
    assert ece_floor(np.array([0.0, 1.0, 1.0])) == 0.0  # certain outcomes: nothing to miss


def miscalibrated(rng: np.random.Generator, n: int) -> tuple[np.ndarray, np.ndarray]:
    """Labels drawn from true probabilities q, and an overconfident, biased model of them."""
    q = rng.uniform(0.02, 0.98, size=n)
    labels = rng.random(n) < q
    logit = np.log(q / (1 - q))
    return labels, 1 / (1 + np.exp(-(2.5 * logit + 0.8)))


def test_platt_and_temperature_scaling_repair_a_miscalibrated_model() -> None:
    rng = np.random.default_rng(51)
    val_labels, val_p = miscalibrated(rng, 20000)
    test_labels, test_p = miscalibrated(rng, 20000)
    before = expected_calibration_error(test_labels, test_p)
    assert before > 0.08
    platt = fit_calibration(val_labels, val_p, "platt", threshold=0.5)
    assert platt.a == pytest.approx(0.4, abs=0.03) and platt.b == pytest.approx(-0.32, abs=0.05)
    calibrated = platt.apply(test_p)
    assert expected_calibration_error(test_labels, calibrated) < 0.02
    assert brier_score(test_labels, calibrated) < brier_score(test_labels, test_p)
    assert roc_auc(test_labels, calibrated) == pytest.approx(roc_auc(test_labels, test_p))
    # the raw threshold keeps its decisions on the calibrated scale
    assert np.array_equal(calibrated >= platt.threshold, test_p >= 0.5)
    temperature = fit_calibration(val_labels, val_p, "temperature", threshold=0.5)
    assert temperature.b == 0.0
    assert expected_calibration_error(test_labels, temperature.apply(test_p)) < before / 2
    again = Calibration.from_json(platt.to_json())
    assert again == platt


def test_bad_calibrations_are_value_errors() -> None:
    with pytest.raises(ValueError, match="unknown calibration"):
        fit_calibration(np.array([True, False]), np.array([0.6, 0.4]), "isotonic", 0.5)
    with pytest.raises(ValueError, match="both classes"):
        fit_calibration(np.array([True, True]), np.array([0.6, 0.4]), "platt", 0.5)
    with pytest.raises(ValueError, match="not a DIP calibration"):
        Calibration.from_json('{"kind": "magic", "a": 1, "b": 0, "threshold": 0.5}')
    none = fit_calibration(np.array([True, False]), np.array([0.6, 0.4]), "none", 0.5)
    assert np.array_equal(none.apply(np.array([0.3])), np.array([0.3]))
