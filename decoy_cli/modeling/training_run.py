"""A whole training run of DIP or DOG, as `decoy train` does it: read the samples (through the
one round loop: failed files and rounds are recorded, the rest is used), split them, train with
early stopping, evaluate on the test part, and write the model folder (model_folder.py) and the
report (metrics JSON with the provenance, the history CSV, the figures).

torch is imported when a run starts, not when this module is imported.
"""

from __future__ import annotations

import csv
import io
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Generic, TypeVar

from decoy_cli.errors import DecoyError
from decoy_cli.files import json_object, write_atomic
from decoy_cli.modeling.network_evaluation import DRAWS
from decoy_cli.modeling.provenance import (
    FileCallback,
    SampleChoice,
    provenance,
    write_json,
)
from decoy_cli.modeling.sample_set import SampleStats
from decoy_cli.modeling.scores import MIN_CELL
from decoy_cli.modeling.split import Split
from decoy_cli.modeling.train_options import (
    BALANCE,
    DEFAULT_BALANCE,
    Balance,
    DogLossWeights,
    TrainOptions,
)

if TYPE_CHECKING:
    from decoy_cli.modeling.training import DipRun, DogRun, EpochRecord, Progress

ProgressCallback = Callable[["Progress"], None]
"""Called after every batch and every epoch of training (`training.Progress`)."""

DIP_THRESHOLD_RULE = "the highest F1 on the validation part"
DOG_DAMAGE_TARGET = "hpDamage summed per pair and step, capped at 100 HP"


RunT = TypeVar("RunT", bound="DipRun | DogRun")


@dataclass(frozen=True)
class TrainingResult(Generic[RunT]):
    """What a run made: the samples it read (`samples` of them, `stats` with the failures),
    their split, the trained model with its test evaluation (`run`), the metadata saved with
    it, and where the model and the report were written."""

    samples: int
    stats: SampleStats
    split: Split
    run: RunT
    metadata: dict[str, object]
    model_folder: Path
    report_folder: Path


def train_dip_model(
    *,
    choice: SampleChoice,
    options: TrainOptions,
    out: Path,
    report: Path | None = None,
    balanced: Balance = DEFAULT_BALANCE,
    on_file: FileCallback | None = None,
    progress: ProgressCallback | None = None,
    units: str = "normalised",
) -> TrainingResult[DipRun]:
    """Train DIP on `choice`'s training part, choose its threshold by the best F1 on the
    validation part, evaluate it on the test part; write `out`/dip.pt and .json and the report
    (default `out`/report)."""
    if balanced not in BALANCE:
        raise DecoyError(f"balance must be one of {', '.join(BALANCE)}, not {balanced!r}")
    samples, stats = choice.read(on_file)
    split = choice.split(samples)

    from decoy_cli.damage.features import FeatureSpec
    from decoy_cli.damage.model_folder import save_dip
    from decoy_cli.modeling.evaluation_figures import write_dip_figures
    from decoy_cli.modeling.training import fit_dip

    run = fit_dip(samples, split, options, FeatureSpec(units=units), balanced, progress)
    metadata: dict[str, object] = {
        **provenance(
            command="dip",
            choice=choice,
            split=split,
            stats=stats,
            options=options,
            samples=samples,
        ),
        "balanced": balanced,
        "threshold_rule": DIP_THRESHOLD_RULE,
        **run.summary(),
    }
    save_dip(out, run.model.net, run.model.spec, run.model.threshold, json_object(metadata))
    folder = report or out / "report"
    write_json(folder / "dip_metrics.json", metadata)
    write_atomic(folder / "dip_history.csv", history_csv(run.trained.history))
    write_dip_figures(run.test, folder, "DIP (test part)")
    return TrainingResult(len(samples), stats, split, run, metadata, out, folder)


def train_dog_model(
    *,
    choice: SampleChoice,
    options: TrainOptions,
    out: Path,
    report: Path | None = None,
    weights: DogLossWeights | None = None,
    draws: int = DRAWS,
    min_cell: int = MIN_CELL,
    on_file: FileCallback | None = None,
    progress: ProgressCallback | None = None,
) -> TrainingResult[DogRun]:
    """Train DOG on the damaging samples of `choice`'s training part (early stopping on those of
    the validation part), evaluate it on those of the test part; write `out`/dog.pt and .json
    and the report (default `out`/report)."""
    if draws < 1 or min_cell < 1:
        raise DecoyError("--draws and --min-cell must be at least 1")
    weights = weights or DogLossWeights()
    samples, stats = choice.read(on_file)
    split = choice.split(samples)

    from decoy_cli.damage.features import FeatureSpec
    from decoy_cli.damage.model_folder import save_dog
    from decoy_cli.modeling.evaluation_figures import write_dog_figures
    from decoy_cli.modeling.training import fit_dog

    run = fit_dog(samples, split, options, FeatureSpec(), weights, draws, min_cell, progress)
    metadata: dict[str, object] = {
        **provenance(
            command="dog",
            choice=choice,
            split=split,
            stats=stats,
            options=options,
            samples=samples,
        ),
        "loss_weights": weights.to_json(),
        "damage_target": DOG_DAMAGE_TARGET,
        **run.summary(),
    }
    save_dog(out, run.model.net, run.model.spec, json_object(metadata))
    folder = report or out / "report"
    write_json(folder / "dog_metrics.json", {**metadata, "cells": run.test.metrics["cells"]})
    write_atomic(folder / "dog_history.csv", history_csv(run.trained.history))
    write_dog_figures(run.test, folder, "DOG (test part)")
    return TrainingResult(len(samples), stats, split, run, metadata, out, folder)


def history_csv(history: list[EpochRecord]) -> bytes:
    """One row per epoch: losses (and DOG's validation loss terms), best marked."""
    names = sorted({k for record in history for k in record.val_parts})
    buffer = io.StringIO()
    writer = csv.writer(buffer)
    writer.writerow(["epoch", "train_loss", "val_loss", *[f"val_{n}" for n in names], "best"])
    for r in history:
        parts = [f"{r.val_parts.get(n, float('nan')):.6f}" for n in names]
        writer.writerow([r.epoch, f"{r.train_loss:.6f}", f"{r.val_loss:.6f}", *parts, int(r.best)])
    return buffer.getvalue().encode()
