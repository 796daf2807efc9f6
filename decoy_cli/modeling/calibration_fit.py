"""How well DIP's probabilities mean what they say, and fitting the map that makes them mean it
(applied at run time by decoy_cli/damage/calibration.py).

A classifier's probability p is calibrated when, among the pairs it gives p, a share p is hit.
Measures (all over held-out samples):

* `brier_score`: mean (p − y)²; 0 is perfect, 0.25 is a coin;
* `expected_calibration_error`: over `BINS` equal-width bins of p, the sample-weighted mean of
  |share hit − mean p| in the bin;
* `reliability_curve`: per bin, the mean p, the share hit and the count (the reliability diagram).

Recalibration, fitted on the validation split (never on the test samples):

* `Platt`: p' = σ(a·logit(p) + b), the two parameters minimising the log loss;
* `Temperature`: p' = σ(logit(p) / T), one parameter (a = 1/T, b = 0).

Both keep the order of the probabilities, so ROC AUC and average precision do not change; the
threshold that gave the best F1 moves with them (`Calibration.threshold`).
"""

from __future__ import annotations

import math

import numpy as np

from decoy_cli.damage.calibration import (
    DECISIONS,
    KINDS,
    Calibration,
    CalibrationKind,
    Decision,
    logit,
)

MIN_RECALL = 0.8
"""Least share of each map's real damaging steps DIP must call hits at the operating point
`decoy models fight-threshold` chooses for the fight (the recall floor; used by
decoy_cli/modeling/fight_threshold.py, kept here so the CLI reads it without loading a world)."""

BINS = 10
"""Equal-width probability bins of the ECE and the reliability curve."""


def _arrays(labels: np.ndarray, probabilities: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    y = np.asarray(labels, dtype=bool)
    p = np.asarray(probabilities, dtype=np.float64)
    if y.shape != p.shape or y.ndim != 1:
        raise ValueError(f"labels and probabilities must be (K,) arrays, got {y.shape}, {p.shape}")
    if len(p) and not (np.isfinite(p).all() and (p >= 0).all() and (p <= 1).all()):
        raise ValueError("probabilities must be finite and within [0, 1]")
    return y, p


def brier_score(labels: np.ndarray, probabilities: np.ndarray) -> float:
    """Mean squared difference of probability and outcome (NaN without samples)."""
    y, p = _arrays(labels, probabilities)
    return float(np.mean((p - y) ** 2)) if len(p) else math.nan


def reliability_curve(
    labels: np.ndarray, probabilities: np.ndarray, bins: int = BINS
) -> list[dict[str, float]]:
    """Per non-empty bin: its edges, the mean probability, the share hit and the count."""
    y, p = _arrays(labels, probabilities)
    index = np.minimum((p * bins).astype(np.int64), bins - 1)
    rows = []
    for b in range(bins):
        inside = index == b
        if inside.any():
            rows.append(
                {
                    "low": b / bins,
                    "high": (b + 1) / bins,
                    "mean_probability": float(p[inside].mean()),
                    "hit_share": float(y[inside].mean()),
                    "count": int(inside.sum()),
                }
            )
    return rows


def expected_calibration_error(
    labels: np.ndarray, probabilities: np.ndarray, bins: int = BINS
) -> float:
    """Sample-weighted mean gap between the share hit and the mean probability per bin."""
    y, p = _arrays(labels, probabilities)
    if not len(p):
        return math.nan
    curve = reliability_curve(y, p, bins)
    return float(
        sum(r["count"] * abs(r["hit_share"] - r["mean_probability"]) for r in curve) / len(p)
    )


FLOOR_DRAWS = 200
"""Label draws per `ece_floor`."""


def ece_floor(probabilities: np.ndarray, bins: int = BINS, seed: int = 0) -> float:
    """The expected calibration error a perfectly calibrated model would show on these samples:
    the mean over `FLOOR_DRAWS` draws of labels hit with exactly these probabilities. On a few
    hundred samples it is far from 0; an ECE near it is as good as the samples can tell."""
    p = np.clip(np.asarray(probabilities, dtype=np.float64).reshape(-1), 0.0, 1.0)
    if not len(p):
        return math.nan
    rng = np.random.default_rng(seed)
    return float(
        np.mean(
            [
                expected_calibration_error(rng.random(len(p)) < p, p, bins)
                for _ in range(FLOOR_DRAWS)
            ]
        )
    )


def _log_loss(y: np.ndarray, z: np.ndarray) -> float:
    # mean of log(1 + exp(-z)) for hits and log(1 + exp(z)) for misses, computed stably
    signed = np.where(y, z, -z)
    return float(np.mean(np.logaddexp(0.0, -signed)))


def fit_calibration(
    labels: np.ndarray,
    probabilities: np.ndarray,
    kind: CalibrationKind,
    threshold: float,
    decision: Decision = "threshold",
) -> Calibration:
    """Fit Platt or temperature scaling on validation samples by minimising the log loss;
    `threshold` (the raw model's) is carried over to the calibrated scale."""
    if decision not in DECISIONS:
        raise ValueError(f"unknown decision {decision!r}: threshold or bernoulli")
    if kind not in KINDS:
        raise ValueError(f"unknown calibration {kind!r}: platt, temperature or none")
    from scipy.optimize import minimize

    y, p = _arrays(labels, probabilities)
    if kind == "none":
        return Calibration("none", 1.0, 0.0, threshold, decision)
    if len(p) < 2 or y.all() or not y.any():
        raise ValueError("calibration needs validation samples of both classes")
    x = logit(p)
    if kind == "platt":
        fitted = minimize(lambda v: _log_loss(y, v[0] * x + v[1]), x0=[1.0, 0.0], method="BFGS")
        a, b = float(fitted.x[0]), float(fitted.x[1])
    else:
        fitted = minimize(lambda v: _log_loss(y, v[0] * x), x0=[1.0], method="BFGS")
        a, b = float(fitted.x[0]), 0.0
    if not a > 0:
        raise ValueError(
            f"the fitted scaling reverses the probabilities (a = {a:.3g}): DIP ranks the "
            "validation samples worse than chance; no calibration"
        )
    moved = float(Calibration(kind, a, b, threshold).apply(np.array([threshold]))[0])
    return Calibration(kind, a, b, moved, decision)


def calibration_scores(
    labels: np.ndarray, probabilities: np.ndarray, calibration: Calibration | None
) -> dict[str, float]:
    """Brier score and expected calibration error of the probabilities, and of the calibrated
    ones (`brier_calibrated`, `ece_calibrated`, and `ece_floor`: what a perfectly calibrated
    model would show on these samples) when there is a calibration."""
    scores = {
        "brier": brier_score(labels, probabilities),
        "ece": expected_calibration_error(labels, probabilities),
    }
    if calibration is not None:
        calibrated = calibration.apply(probabilities)
        scores["brier_calibrated"] = brier_score(labels, calibrated)
        scores["ece_calibrated"] = expected_calibration_error(labels, calibrated)
        scores["ece_floor"] = ece_floor(calibrated)
    return scores
