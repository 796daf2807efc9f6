"""DIP's calibration as the simulator applies it: `Calibration`, read from a model folder's
`dip_calibration.json`.

p' = σ(a·logit(p) + b): Platt scaling (a and b) or temperature scaling (a = 1/T, b = 0), fitted
on validation rounds by `decoy models calibrate` (decoy_cli/modeling/calibration_fit.py, with
the measures of how calibrated a model is). Both keep the order of the probabilities; the
threshold that gave the best F1 moves with them (`Calibration.threshold`).

The combat step decides a pair's hit from the calibrated probability by `Calibration.decide`:
"threshold" (the paper's rule: a hit when p' reaches the threshold, the same pairs as the raw
model at its threshold) or "bernoulli" (a hit with probability p', so the share of pairs hit
matches the data's in expectation).
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass
from typing import Literal, get_args

import numpy as np

_EPS = 1e-6


def logit(p: np.ndarray) -> np.ndarray:
    """log(p / (1 - p)), with p clipped away from 0 and 1."""
    q = np.clip(p, _EPS, 1 - _EPS)
    return np.log(q / (1 - q))


CALIBRATION_FILE = "dip_calibration.json"
"""A model folder's DIP calibration (`decoy models calibrate`, `decoy models fight-threshold`)."""

Decision = Literal["threshold", "bernoulli"]
CalibrationKind = Literal["platt", "temperature", "none"]
DECISIONS: tuple[Decision, ...] = get_args(Decision)
KINDS: tuple[CalibrationKind, ...] = get_args(CalibrationKind)


@dataclass(frozen=True)
class Calibration:
    """p' = σ(a·logit(p) + b), its kind ("platt", "temperature" or "none"), the decision
    threshold on the calibrated probability and the combat step's decision rule."""

    kind: CalibrationKind
    a: float
    b: float
    threshold: float
    decision: Decision = "threshold"

    def decide(self, probabilities: np.ndarray, rng: np.random.Generator) -> np.ndarray:
        """(K,) bool: which pairs hit, by `decision` on the calibrated probabilities."""
        calibrated = self.apply(probabilities)
        if self.decision == "bernoulli":
            return rng.random(len(calibrated)) < calibrated
        return calibrated >= self.threshold

    def apply(self, probabilities: np.ndarray) -> np.ndarray:
        """The calibrated probabilities."""
        if self.kind == "none":
            return np.asarray(probabilities, dtype=np.float64)
        z = self.a * logit(np.asarray(probabilities, dtype=np.float64)) + self.b
        return 1.0 / (1.0 + np.exp(-z))

    def to_json(self) -> str:
        return json.dumps(
            {
                "kind": self.kind,
                "a": self.a,
                "b": self.b,
                "threshold": self.threshold,
                "decision": self.decision,
            }
        )

    @classmethod
    def from_json(cls, text: str) -> Calibration:
        """A calibration written by `to_json`; anything else is a ValueError."""
        return cls.from_dict(json.loads(text))

    @classmethod
    def from_dict(cls, data: object) -> Calibration:
        """A calibration as `to_json` writes it, already parsed; anything else (a field
        missing, not a number, not finite, a threshold outside [0, 1]) is a ValueError naming
        the field."""
        if not isinstance(data, dict) or data.get("kind") not in KINDS:
            kind = data.get("kind") if isinstance(data, dict) else None
            raise ValueError(f"not a DIP calibration: kind {kind!r}")
        if not all(k in data for k in ("a", "b", "threshold")):
            raise ValueError("a DIP calibration needs a, b and threshold")
        for key in ("a", "b", "threshold"):
            value = data[key]
            if isinstance(value, bool) or not isinstance(value, int | float):
                raise ValueError(f"{key} must be a number, not {type(value).__name__}")
        a, b, threshold = (float(data[k]) for k in ("a", "b", "threshold"))
        if not all(math.isfinite(v) for v in (a, b, threshold)) or not 0 <= threshold <= 1:
            raise ValueError("a DIP calibration with non-finite parameters or threshold")
        decision = data.get("decision", "threshold")
        if decision not in DECISIONS:
            raise ValueError(f"unknown decision {decision!r}: threshold or bernoulli")
        return cls(data["kind"], a, b, threshold, decision)
