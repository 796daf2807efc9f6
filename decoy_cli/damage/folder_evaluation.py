"""Scoring a model folder (trained or imported) on ESTA data, as `decoy models evaluate` does:
DIP's and DOG's metrics on all samples or on one part of a split, written with the figures to
an output folder (metrics.json).

DIP is scored on a 1:1 balanced set by default (the paper's), DOG on the damaging samples.
torch is imported when the models are loaded, not when this module is imported.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from decoy_cli.damage.evaluation import DRAWS, DipEvaluation, DogEvaluation
from decoy_cli.damage.provenance import FileCallback, SampleChoice, write_json
from decoy_cli.damage.sample_set import SampleStats
from decoy_cli.damage.scores import MIN_CELL
from decoy_cli.damage.split import balance
from decoy_cli.errors import ModelError

DEFAULT_SUBSET = "all"
"""Score on every sample; or "train", "val", "test": that part of the split."""
BALANCED = True
"""DIP is scored on all positives and as many random negatives (the paper's 1:1)."""


@dataclass(frozen=True)
class FolderEvaluation:
    """What scoring a model folder gave: its name, the samples read (`stats` with the
    failures), DIP's and DOG's evaluations (None for a model the folder lacks), the report
    written to `out`/metrics.json and the figures."""

    name: str
    subset: str
    samples: int
    stats: SampleStats
    dip: DipEvaluation | None
    dog: DogEvaluation | None
    report: dict[str, Any]
    out: Path
    figures: list[Path]


def evaluate_model_folder(
    *,
    folder: Path,
    choice: SampleChoice,
    out: Path,
    subset: str = DEFAULT_SUBSET,
    balanced: bool = BALANCED,
    threshold: float | None = None,
    draws: int = DRAWS,
    min_cell: int = MIN_CELL,
    on_file: FileCallback | None = None,
) -> FolderEvaluation:
    """Score the DIP and/or DOG of `folder` on `choice`'s samples (all, or the `subset` part
    of its split) and write metrics.json and the figures to `out`. A folder without models, a
    bad option, or a subset without damaging samples is one ModelError line."""
    if not folder.is_dir():
        raise ModelError(f"{folder}: no such model folder")
    has_dip = (folder / "dip.json").is_file()
    has_dog = (folder / "dog.json").is_file()
    if not (has_dip or has_dog):
        raise ModelError(f"{folder}: holds neither dip.json nor dog.json")
    if threshold is not None and not 0.0 <= threshold <= 1.0:
        raise ModelError(f"--threshold must be a probability in [0, 1], not {threshold}")
    if draws < 1 or min_cell < 1:
        raise ModelError("--draws and --min-cell must be at least 1")
    samples, stats = choice.read(on_file)
    index = np.arange(len(samples)) if subset == "all" else choice.split(samples).part(subset)

    from decoy_cli.damage.evaluation import evaluate_dip, evaluate_dog
    from decoy_cli.damage.evaluation_figures import write_dip_figures, write_dog_figures
    from decoy_cli.damage.model_folder import load_dip, load_dog

    report: dict[str, Any] = {
        "model_folder": str(folder),
        "data": [str(d) for d in choice.data],
        "subset": subset,
        "split": None if subset == "all" else {"by": choice.split_by, "seed": choice.seed},
        "mode": choice.mode,
        "window_s": choice.window_s,
        "sample_stats": stats.to_json(),
    }
    figures: list[Path] = []
    name = folder.name or str(folder)
    dip_result = dog_result = None
    if has_dip:
        dip = load_dip(folder)
        chosen = balance(samples, index, choice.seed) if balanced else index
        if not samples.hit[chosen].any():
            raise ModelError(f"no damaging samples in the {subset} samples: DIP cannot be scored")
        dip_result = evaluate_dip(dip, samples.take(chosen), threshold)
        report["dip"] = {"balanced": balanced, **dip_result.metrics}
        figures += write_dip_figures(dip_result, out, f"DIP of {name}")
    if has_dog:
        dog = load_dog(folder)
        chosen = index[samples.hit[index]]
        if len(chosen) == 0:
            raise ModelError(f"no damaging samples in the {subset} samples: DOG cannot be scored")
        dog_result = evaluate_dog(dog, samples.take(chosen), choice.seed, draws, min_cell)
        report["dog"] = dog_result.metrics
        figures += write_dog_figures(dog_result, out, f"DOG of {name}")
    write_json(out / "metrics.json", report)
    return FolderEvaluation(
        name, subset, len(samples), stats, dip_result, dog_result, report, out, figures
    )
