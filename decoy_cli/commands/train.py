"""`decoy train dip|dog DATA...`: train the damage models on ESTA data.

Parses the options, runs one training (decoy_cli/damage/training_run.py: read the samples,
split them by match or round, train with early stopping, evaluate on the test part, write the
model folder and the report) and prints what it gave.
"""

from __future__ import annotations

from pathlib import Path
from typing import Literal

import typer
from rich.console import Console

from decoy_cli.commands._console import make_console
from decoy_cli.commands._damage_output import (
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
    print_samples,
    progress_bars,
)
from decoy_cli.damage.evaluation import DRAWS
from decoy_cli.damage.provenance import SampleChoice
from decoy_cli.damage.samples import DEFAULT_MODE, DEFAULT_WINDOW_S
from decoy_cli.damage.scores import MIN_CELL
from decoy_cli.damage.split import (
    DEFAULT_SEED,
    DEFAULT_SPLIT,
    DEFAULT_TEST_FRACTION,
    DEFAULT_VAL_FRACTION,
)
from decoy_cli.damage.train_options import (
    BATCH_SIZE,
    DAMAGE_WEIGHT,
    DEFAULT_BALANCE,
    DIP_EPOCHS,
    DOG_EPOCHS,
    HIT_GROUP_WEIGHT,
    KL_WEIGHT,
    LEARNING_RATE,
    PATIENCE,
    THREADS,
    XAVIER,
    DogLossWeights,
    TrainOptions,
)
from decoy_cli.damage.training_run import TrainingResult, train_dip_model, train_dog_model
from decoy_cli.files import check_folder_writable

DEFAULT_OUT = Path("decoy-out") / "models" / "trained"

app = typer.Typer(
    help="Train the damage models (DIP: does a shot land; DOG: how much and where) on ESTA data.",
    no_args_is_help=True,
)

REPORT_HELP = "Folder for metrics, history and figures (default OUT/report)."
PATIENCE_HELP = "Stop after this many epochs without a better validation loss."
XAVIER_HELP = "Xavier-uniform initial weights (the paper's)."
THREADS_HELP = "torch threads (1 is fastest for these small networks)."


def _print_start(console: Console, result: TrainingResult, choice: SampleChoice) -> None:
    """The samples read, the failed inputs and the split."""
    print_samples(console, result.samples, result.stats)
    console.print(
        f"split by {choice.split_by} (seed {choice.seed}): "
        + ", ".join(f"{len(units)} {name}" for name, units in result.split.units.items())
    )


@app.command("dip")
def dip(
    data: list[Path] = typer.Argument(..., help=DATA_HELP),
    out: Path = typer.Option(DEFAULT_OUT, "--out", help="Model folder to write dip.pt/json in."),
    report: Path | None = typer.Option(None, "--report", help=REPORT_HELP),
    seed: int = typer.Option(DEFAULT_SEED, "--seed", help=SEED_HELP),
    epochs: int = typer.Option(DIP_EPOCHS, "--epochs", help="Most epochs (the paper's)."),
    batch_size: int = typer.Option(BATCH_SIZE, "--batch-size", help="Mini-batch size (paper's)."),
    learning_rate: float = typer.Option(
        LEARNING_RATE, "--lr", help="Adam learning rate (paper's)."
    ),
    patience: int = typer.Option(PATIENCE, "--patience", help=PATIENCE_HELP),
    split_by: str = typer.Option(DEFAULT_SPLIT, "--split", help=SPLIT_HELP),
    val_fraction: float = typer.Option(DEFAULT_VAL_FRACTION, "--val-fraction", help=VAL_HELP),
    test_fraction: float = typer.Option(DEFAULT_TEST_FRACTION, "--test-fraction", help=TEST_HELP),
    mode: str = typer.Option(DEFAULT_MODE, "--mode", help=MODE_HELP),
    window: float = typer.Option(DEFAULT_WINDOW_S, "--window", help=WINDOW_HELP),
    balanced: str = typer.Option(
        DEFAULT_BALANCE,
        "--balance",
        help="1:1 balancing of positives and negatives: all parts (the paper's), eval (train "
        "on every sample, balance validation and test) or none.",
    ),
    xavier: bool = typer.Option(XAVIER, "--xavier/--no-xavier", help=XAVIER_HELP),
    threads: int = typer.Option(THREADS, "--threads", help=THREADS_HELP),
    units: Literal["normalised", "relative"] = typer.Option(
        "normalised",
        "--units",
        help="Features: normalised (positions in the de_dust2 box, the map one-hot, as the "
        "paper's layout) or relative (distance, height difference and bearings only: nothing "
        "that names a place on one map).",
    ),
) -> None:
    """Train DIP, the Damage Indicator Predictor (does a shot land in a 0.5 s step).

    Binary cross-entropy with early stopping on the validation part; the decision threshold is
    the best F1 on the validation part; test metrics are printed and saved with the model."""
    options = TrainOptions(
        epochs=epochs,
        batch_size=batch_size,
        learning_rate=learning_rate,
        patience=patience,
        seed=seed,
        xavier=xavier,
        threads=threads,
    )
    choice = SampleChoice(
        data=data,
        mode=mode,
        window_s=window,
        split_by=split_by,
        seed=seed,
        val_fraction=val_fraction,
        test_fraction=test_fraction,
    )
    _check_outputs(out, report)
    bars, on_file, on_step = progress_bars()
    with bars:
        result = train_dip_model(
            choice=choice,
            options=options,
            out=out,
            report=report,
            balanced=balanced,
            on_file=on_file,
            progress=on_step,
            units=units,
        )
    console = make_console()
    _print_start(console, result, choice)
    run = result.run
    console.print(
        f"best epoch {run.trained.best_epoch} of {len(run.trained.history)}; threshold "
        f"{run.model.threshold:.3f} (best F1 on validation)"
    )
    console.print(dip_table(run.test.metrics, "DIP on the test part"))
    console.print(f"model written to {result.model_folder}, report to {result.report_folder}")


@app.command("dog")
def dog(
    data: list[Path] = typer.Argument(..., help=DATA_HELP),
    out: Path = typer.Option(DEFAULT_OUT, "--out", help="Model folder to write dog.pt/json in."),
    report: Path | None = typer.Option(None, "--report", help=REPORT_HELP),
    seed: int = typer.Option(DEFAULT_SEED, "--seed", help=SEED_HELP),
    epochs: int = typer.Option(DOG_EPOCHS, "--epochs", help="Most epochs (the paper's)."),
    batch_size: int = typer.Option(BATCH_SIZE, "--batch-size", help="Mini-batch size (paper's)."),
    learning_rate: float = typer.Option(
        LEARNING_RATE, "--lr", help="Adam learning rate (paper's)."
    ),
    patience: int = typer.Option(PATIENCE, "--patience", help=PATIENCE_HELP),
    split_by: str = typer.Option(DEFAULT_SPLIT, "--split", help=SPLIT_HELP),
    val_fraction: float = typer.Option(DEFAULT_VAL_FRACTION, "--val-fraction", help=VAL_HELP),
    test_fraction: float = typer.Option(DEFAULT_TEST_FRACTION, "--test-fraction", help=TEST_HELP),
    mode: str = typer.Option(DEFAULT_MODE, "--mode", help=MODE_HELP),
    window: float = typer.Option(DEFAULT_WINDOW_S, "--window", help=WINDOW_HELP),
    damage_weight: float = typer.Option(
        DAMAGE_WEIGHT, "--damage-weight", help="Weight of the damage MSE in the loss."
    ),
    hit_group_weight: float = typer.Option(
        HIT_GROUP_WEIGHT, "--hit-group-weight", help="Weight of the hit-group cross-entropy."
    ),
    kl_weight: float = typer.Option(KL_WEIGHT, "--kl-weight", help="Weight of the KL term."),
    draws: int = typer.Option(DRAWS, "--draws", help=DRAWS_HELP),
    min_cell: int = typer.Option(MIN_CELL, "--min-cell", help=MIN_CELL_HELP),
    xavier: bool = typer.Option(XAVIER, "--xavier/--no-xavier", help=XAVIER_HELP),
    threads: int = typer.Option(THREADS, "--threads", help=THREADS_HELP),
) -> None:
    """Train DOG, the Damage Outcome Generator (how much damage, which hit group).

    A conditional VAE trained on the damaging samples with early stopping on the validation
    part; test metrics are printed and saved with the model."""
    weights = DogLossWeights(damage=damage_weight, hit_group=hit_group_weight, kl=kl_weight)
    options = TrainOptions(
        epochs=epochs,
        batch_size=batch_size,
        learning_rate=learning_rate,
        patience=patience,
        seed=seed,
        xavier=xavier,
        threads=threads,
    )
    choice = SampleChoice(
        data=data,
        mode=mode,
        window_s=window,
        split_by=split_by,
        seed=seed,
        val_fraction=val_fraction,
        test_fraction=test_fraction,
    )
    _check_outputs(out, report)
    bars, on_file, on_step = progress_bars()
    with bars:
        result = train_dog_model(
            choice=choice,
            options=options,
            out=out,
            report=report,
            weights=weights,
            draws=draws,
            min_cell=min_cell,
            on_file=on_file,
            progress=on_step,
        )
    console = make_console()
    _print_start(console, result, choice)
    run = result.run
    console.print(f"best epoch {run.trained.best_epoch} of {len(run.trained.history)}")
    console.print(dog_table(run.test.metrics, "DOG on the test part"))
    if run.test.metrics["cells"]:
        console.print(cells_table(run.test.metrics["cells"]))
    console.print(f"model written to {result.model_folder}, report to {result.report_folder}")


def _check_outputs(out: Path, report: Path | None) -> None:
    """Fail before training when the model or report folder cannot be written."""
    check_folder_writable(out)
    if report is not None:
        check_folder_writable(report)
