"""`decoy train dip|dog DATA...`: train the damage models on ESTA data.

Each command reads the samples (decoy_cli/damage/samples.py), splits them by match or round,
trains with early stopping on the validation part (decoy_cli/damage/training.py), evaluates on
the test part, and writes the model into a model folder (`--out`, the format of
decoy_cli/damage/model_folder.py) and a report (`--report`: metrics JSON, history CSV, figures).
"""

from __future__ import annotations

import csv
import io
from pathlib import Path
from typing import Any

import typer
from rich.console import Console
from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeElapsedColumn

from decoy_cli import __version__
from decoy_cli.commands.model_evaluation import (
    DATA_HELP,
    DRAWS_HELP,
    MIN_CELL_HELP,
    MODE_HELP,
    SEED_HELP,
    SPLIT_HELP,
    TEST_HELP,
    VAL_HELP,
    WINDOW_HELP,
    cells_table,
    dip_table,
    dog_table,
    json_ready,
    load_samples,
    write_json,
)
from decoy_cli.damage.evaluation import DRAWS
from decoy_cli.damage.samples import DEFAULT_WINDOW_S, SampleStats, Split, split_samples
from decoy_cli.damage.scores import MIN_CELL
from decoy_cli.errors import DecoyError
from decoy_cli.files import write_atomic

DEFAULT_OUT = Path("decoy-out") / "models" / "trained"

app = typer.Typer(
    help="Train the damage models (DIP: does a shot land; DOG: how much and where) on ESTA data.",
    no_args_is_help=True,
)


def _progress_bar() -> tuple[Progress, Any]:
    """A progress bar over all batches of all epochs, and the callback that drives it."""
    errors = Console(stderr=True)  # drawn only on a terminal: no stray lines in pipes
    progress = Progress(
        TextColumn("{task.description}"),
        BarColumn(),
        MofNCompleteColumn(),
        TimeElapsedColumn(),
        console=errors,
        transient=True,
        disable=not errors.is_terminal,
    )
    task = progress.add_task("training", total=None)
    state = {"val": "–"}

    def update(step: Any) -> None:
        if step.record is not None:
            state["val"] = f"{step.record.val_loss:.4f}"
        progress.update(
            task,
            total=step.epochs * step.batches,
            completed=(step.epoch - 1) * step.batches + step.batch,
            description=f"epoch {step.epoch}/{step.epochs}, validation loss {state['val']}",
        )

    return progress, update


def _history_csv(history: list[Any]) -> bytes:
    """One row per epoch: losses (and DOG's validation loss terms), best marked."""
    names = sorted({k for record in history for k in record.val_parts})
    buffer = io.StringIO()
    writer = csv.writer(buffer)
    writer.writerow(["epoch", "train_loss", "val_loss", *[f"val_{n}" for n in names], "best"])
    for r in history:
        parts = [f"{r.val_parts.get(n, float('nan')):.6f}" for n in names]
        writer.writerow([r.epoch, f"{r.train_loss:.6f}", f"{r.val_loss:.6f}", *parts, int(r.best)])
    return buffer.getvalue().encode()


def _provenance(
    command: str,
    data: list[Path],
    mode: str,
    window: float,
    split: Split,
    split_by: str,
    seed: int,
    fractions: tuple[float, float],
    stats: SampleStats,
    options: Any,
) -> dict[str, Any]:
    """What the model was trained on and how: kept in the model's JSON metadata."""
    return {
        "trained_with": f"decoy {__version__}: decoy train {command}",
        "data": [str(d) for d in data],
        "mode": mode,
        "window_s": window,
        "split": {
            "by": split_by,
            "seed": seed,
            "val_fraction": fractions[0],
            "test_fraction": fractions[1],
            "units": split.units,
        },
        "sample_stats": stats.to_json(),
        "options": {k: getattr(options, k) for k in options.__dataclass_fields__},
    }


def _common(
    data: list[Path],
    mode: str,
    window: float,
    split_by: str,
    seed: int,
    val_fraction: float,
    test_fraction: float,
) -> tuple[Console, Any, SampleStats, Split]:
    """Read and split the samples (what both commands do first)."""
    console = Console()
    samples, stats = load_samples(console, data, mode, window)
    split = split_samples(samples, split_by, seed, val_fraction, test_fraction)
    console.print(
        f"split by {split_by} (seed {seed}): "
        + ", ".join(f"{len(units)} {name}" for name, units in split.units.items())
    )
    return console, samples, stats, split


@app.command("dip")
def dip(
    data: list[Path] = typer.Argument(..., help=DATA_HELP),
    out: Path = typer.Option(DEFAULT_OUT, "--out", help="Model folder to write dip.pt/json in."),
    report: Path | None = typer.Option(
        None, "--report", help="Folder for metrics, history and figures (default OUT/report)."
    ),
    seed: int = typer.Option(0, "--seed", help=SEED_HELP),
    epochs: int = typer.Option(20, "--epochs", help="Most epochs (the paper: 20)."),
    batch_size: int = typer.Option(256, "--batch-size", help="Mini-batch size (the paper: 256)."),
    learning_rate: float = typer.Option(3e-4, "--lr", help="Adam learning rate (paper: 3e-4)."),
    patience: int = typer.Option(
        5, "--patience", help="Stop after this many epochs without a better validation loss."
    ),
    split_by: str = typer.Option("match", "--split", help=SPLIT_HELP),
    val_fraction: float = typer.Option(0.15, "--val-fraction", help=VAL_HELP),
    test_fraction: float = typer.Option(0.15, "--test-fraction", help=TEST_HELP),
    mode: str = typer.Option("auto", "--mode", help=MODE_HELP),
    window: float = typer.Option(DEFAULT_WINDOW_S, "--window", help=WINDOW_HELP),
    balanced: str = typer.Option(
        "all",
        "--balance",
        help="1:1 balancing of positives and negatives: all parts (the paper's), eval (train "
        "on every sample, balance validation and test) or none.",
    ),
    xavier: bool = typer.Option(
        True, "--xavier/--no-xavier", help="Xavier-uniform initial weights (the paper's)."
    ),
    threads: int = typer.Option(
        1, "--threads", help="torch threads (1 is fastest for these small networks)."
    ),
) -> None:
    """Train DIP, the Damage Indicator Predictor (does a shot land in a 0.5 s step).

    Binary cross-entropy with early stopping on the validation part; the decision threshold is
    the best F1 on the validation part; test metrics are printed and saved with the model."""
    from decoy_cli.damage.evaluation_figures import write_dip_figures
    from decoy_cli.damage.features import FeatureSpec
    from decoy_cli.damage.model_folder import save_dip
    from decoy_cli.damage.training import TrainOptions, fit_dip

    options = TrainOptions(epochs, batch_size, learning_rate, patience, seed, xavier, threads)
    console, samples, stats, split = _common(
        data, mode, window, split_by, seed, val_fraction, test_fraction
    )
    progress, update = _progress_bar()
    with progress:
        run = fit_dip(samples, split, options, FeatureSpec(), balanced, update)
    metadata = {
        **_provenance(
            "dip",
            data,
            mode,
            window,
            split,
            split_by,
            seed,
            (val_fraction, test_fraction),
            stats,
            options,
        ),
        "balanced": balanced,
        "threshold_rule": "the highest F1 on the validation part",
        **run.summary(),
    }
    save_dip(out, run.model.net, run.model.spec, run.model.threshold, json_ready(metadata))
    folder = report or out / "report"
    write_json(folder / "dip_metrics.json", metadata)
    write_atomic(folder / "dip_history.csv", _history_csv(run.trained.history))
    write_dip_figures(run.test, folder, "DIP (test part)")
    console.print(
        f"best epoch {run.trained.best_epoch} of {len(run.trained.history)}; threshold "
        f"{run.model.threshold:.3f} (best F1 on validation)"
    )
    console.print(dip_table(run.test.metrics, "DIP on the test part"))
    console.print(f"model written to {out}, report to {folder}")


@app.command("dog")
def dog(
    data: list[Path] = typer.Argument(..., help=DATA_HELP),
    out: Path = typer.Option(DEFAULT_OUT, "--out", help="Model folder to write dog.pt/json in."),
    report: Path | None = typer.Option(
        None, "--report", help="Folder for metrics, history and figures (default OUT/report)."
    ),
    seed: int = typer.Option(0, "--seed", help=SEED_HELP),
    epochs: int = typer.Option(50, "--epochs", help="Most epochs (the paper: 50)."),
    batch_size: int = typer.Option(256, "--batch-size", help="Mini-batch size (the paper: 256)."),
    learning_rate: float = typer.Option(3e-4, "--lr", help="Adam learning rate (paper: 3e-4)."),
    patience: int = typer.Option(
        5, "--patience", help="Stop after this many epochs without a better validation loss."
    ),
    split_by: str = typer.Option("match", "--split", help=SPLIT_HELP),
    val_fraction: float = typer.Option(0.15, "--val-fraction", help=VAL_HELP),
    test_fraction: float = typer.Option(0.15, "--test-fraction", help=TEST_HELP),
    mode: str = typer.Option("auto", "--mode", help=MODE_HELP),
    window: float = typer.Option(DEFAULT_WINDOW_S, "--window", help=WINDOW_HELP),
    damage_weight: float = typer.Option(
        1.0, "--damage-weight", help="Weight of the damage MSE in the loss."
    ),
    hit_group_weight: float = typer.Option(
        0.7, "--hit-group-weight", help="Weight of the hit-group cross-entropy (the paper: 0.7)."
    ),
    kl_weight: float = typer.Option(0.2, "--kl-weight", help="Weight of the KL term (paper: 0.2)."),
    draws: int = typer.Option(DRAWS, "--draws", help=DRAWS_HELP),
    min_cell: int = typer.Option(MIN_CELL, "--min-cell", help=MIN_CELL_HELP),
    xavier: bool = typer.Option(
        True, "--xavier/--no-xavier", help="Xavier-uniform initial weights (the paper's)."
    ),
    threads: int = typer.Option(
        1, "--threads", help="torch threads (1 is fastest for these small networks)."
    ),
) -> None:
    """Train DOG, the Damage Outcome Generator (how much damage, which hit group).

    A conditional VAE trained on the damaging samples with early stopping on the validation
    part; test metrics are printed and saved with the model."""
    from decoy_cli.damage.evaluation_figures import write_dog_figures
    from decoy_cli.damage.features import FeatureSpec
    from decoy_cli.damage.model_folder import save_dog
    from decoy_cli.damage.networks import DogLossWeights
    from decoy_cli.damage.training import TrainOptions, fit_dog

    for name, value in (("damage", damage_weight), ("hit-group", hit_group_weight)):
        if not value >= 0:
            raise DecoyError(f"the {name} weight must not be negative, not {value}")
    if not kl_weight >= 0:
        raise DecoyError(f"the KL weight must not be negative, not {kl_weight}")
    if draws < 1 or min_cell < 1:
        raise DecoyError("--draws and --min-cell must be at least 1")
    options = TrainOptions(epochs, batch_size, learning_rate, patience, seed, xavier, threads)
    weights = DogLossWeights(damage_weight, hit_group_weight, kl_weight)
    console, samples, stats, split = _common(
        data, mode, window, split_by, seed, val_fraction, test_fraction
    )
    progress, update = _progress_bar()
    with progress:
        run = fit_dog(samples, split, options, FeatureSpec(), weights, draws, min_cell, update)
    metadata = {
        **_provenance(
            "dog",
            data,
            mode,
            window,
            split,
            split_by,
            seed,
            (val_fraction, test_fraction),
            stats,
            options,
        ),
        "loss_weights": {"damage": damage_weight, "hit_group": hit_group_weight, "kl": kl_weight},
        "damage_target": "hpDamage summed per pair and step, capped at 100 HP",
        **run.summary(),
    }
    save_dog(out, run.model.net, run.model.spec, json_ready(metadata))
    folder = report or out / "report"
    write_json(folder / "dog_metrics.json", {**metadata, "cells": run.test.metrics["cells"]})
    write_atomic(folder / "dog_history.csv", _history_csv(run.trained.history))
    write_dog_figures(run.test, folder, "DOG (test part)")
    console.print(f"best epoch {run.trained.best_epoch} of {len(run.trained.history)}")
    console.print(dog_table(run.test.metrics, "DOG on the test part"))
    if run.test.metrics["cells"]:
        console.print(cells_table(run.test.metrics["cells"]))
    console.print(f"model written to {out}, report to {folder}")
