"""Calibrating a model folder's DIP on ESTA data, as `decoy models calibrate` does.

The map (Platt or temperature scaling, decoy_cli/damage/calibration.py) is fitted on the
validation part of the split at the data's own share of damaging pairs (not balanced: the
simulator meets pairs at that share) and written into the folder as `dip_calibration.json`, which
`load_dip` reads and `decoy models evaluate` reports. The test part measures it before and after.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from decoy_cli.damage.calibration import Calibration, CalibrationKind, Decision
from decoy_cli.errors import ModelError
from decoy_cli.modeling.calibration_fit import calibration_scores, fit_calibration
from decoy_cli.modeling.provenance import FileCallback, SampleChoice
from decoy_cli.modeling.sample_set import SampleStats
from decoy_cli.modeling.split import SplitPart

PARTS: tuple[SplitPart, ...] = ("val", "test")


@dataclass(frozen=True)
class CalibrationResult:
    """The fitted map, where it was written, and Brier / ECE before and after by part."""

    calibration: Calibration
    replaced: Calibration | None
    """The folder's calibration before (this one replaces it; its fight threshold, if it set
    one, carries over onto the new scale)."""
    path: Path
    scores: dict[str, dict[str, float]]
    """part -> brier, ece, brier_calibrated, ece_calibrated, samples, positives."""
    stats: SampleStats


def calibrate_dip_folder(
    *,
    folder: Path,
    choice: SampleChoice,
    kind: CalibrationKind,
    decision: Decision = "threshold",
    on_file: FileCallback | None = None,
) -> CalibrationResult:
    """Fit the DIP calibration of `folder` on the validation samples and save it (module doc).
    A folder without a DIP or a part without both classes is one ModelError line."""
    if not (folder / "dip.json").is_file():
        raise ModelError(f"{folder}: holds no dip.json to calibrate")
    from decoy_cli.damage.model_folder import load_dip, save_calibration
    from decoy_cli.modeling.network_evaluation import dip_probabilities

    samples, stats = choice.read(on_file)
    split = choice.split(samples)
    dip = load_dip(folder)
    parts = {}
    for part in PARTS:
        index = split.part(part)
        labels = samples.hit[index]
        if not (labels.any() and (~labels).any()):
            raise ModelError(f"the {part} samples lack hits or misses: no calibration")
        parts[part] = (labels, dip_probabilities(dip, samples.take(index)))
    try:
        calibration = fit_calibration(
            *parts["val"], kind=kind, threshold=dip.decision_threshold, decision=decision
        )
    except ValueError as error:
        raise ModelError(str(error)) from None
    scores: dict[str, dict[str, float]] = {}
    for part, (labels, probabilities) in parts.items():
        scores[part] = {
            "samples": float(len(labels)),
            "positives": float(np.sum(labels)),
            **calibration_scores(labels, probabilities, calibration),
        }
    path = save_calibration(folder, calibration)
    return CalibrationResult(calibration, dip.calibration, path, scores, stats)
