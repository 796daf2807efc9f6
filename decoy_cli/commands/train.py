"""`decoy train dip|dog DATA...`: train the damage models on ESTA data.

Parses the options, runs one training (decoy_cli/modeling/training_run.py: read the samples,
split them by match or round, train with early stopping, evaluate on the test part, write the
model folder and the report) and prints what it gave.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Annotated, Literal

import typer
from rich.console import Console

from decoy_cli.commands._console import make_console
from decoy_cli.commands._damage_output import (
    DATA_HELP,
    DRAWS_HELP,
    MIN_CELL_HELP,
    cells_table,
    dip_table,
    dog_table,
    print_samples,
    progress_bars,
)
from decoy_cli.commands._groups import with_groups
from decoy_cli.commands._options import SampleOptions
from decoy_cli.damage.calibration import CALIBRATION_FILE
from decoy_cli.files import check_folder_writable
from decoy_cli.modeling.network_evaluation import DRAWS
from decoy_cli.modeling.provenance import SampleChoice
from decoy_cli.modeling.scores import MIN_CELL
from decoy_cli.modeling.train_options import (
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
    Balance,
    DogLossWeights,
    TrainOptions,
)
from decoy_cli.modeling.training_run import TrainingResult, train_dip_model, train_dog_model

DEFAULT_OUT = Path("decoy-out") / "models" / "trained"

app = typer.Typer(
    help="Train the damage models (DIP: does a shot land; DOG: how much and where) on ESTA data.",
    no_args_is_help=True,
)

REPORT_HELP = "Folder for metrics, history and figures (default OUT/report)."


@dataclass(frozen=True)
class Fitting:
    """How both networks are fitted, but for the number of epochs (the paper's differ)."""

    batch_size: Annotated[int, typer.Option("--batch-size", help="Mini-batch size (paper's).")] = (
        BATCH_SIZE
    )
    learning_rate: Annotated[float, typer.Option("--lr", help="Adam learning rate (paper's).")] = (
        LEARNING_RATE
    )
    patience: Annotated[
        int,
        typer.Option(
            "--patience", help="Stop after this many epochs without a better validation loss."
        ),
    ] = PATIENCE
    xavier: Annotated[
        bool,
        typer.Option("--xavier/--no-xavier", help="Xavier-uniform initial weights (the paper's)."),
    ] = XAVIER
    threads: Annotated[
        int,
        typer.Option("--threads", help="torch threads (1 is fastest for these small networks)."),
    ] = THREADS

    def options(self, epochs: int, seed: int) -> TrainOptions:
        """The library's training options: these, `epochs` and `seed`."""
        return TrainOptions(
            epochs=epochs,
            batch_size=self.batch_size,
            learning_rate=self.learning_rate,
            patience=self.patience,
            seed=seed,
            xavier=self.xavier,
            threads=self.threads,
        )


def _print_start(console: Console, result: TrainingResult, choice: SampleChoice) -> None:
    """The samples read, the failed inputs and the split."""
    print_samples(console, result.samples, result.stats)
    console.print(
        f"split by {choice.split_by} (seed {choice.seed}): "
        + ", ".join(f"{len(units)} {name}" for name, units in result.split.units.items())
    )


@app.command("dip")
@with_groups
def dip(
    data: list[Path] = typer.Argument(..., help=DATA_HELP),
    out: Path = typer.Option(DEFAULT_OUT, "--out", help="Model folder to write dip.pt/json in."),
    report: Path | None = typer.Option(None, "--report", help=REPORT_HELP),
    epochs: int = typer.Option(DIP_EPOCHS, "--epochs", help="Most epochs (the paper's)."),
    fitting: Fitting = Fitting(),
    samples: SampleOptions = SampleOptions(),
    balanced: Balance = typer.Option(
        DEFAULT_BALANCE,
        "--balance",
        help="1:1 balancing of positives and negatives: all parts (the paper's), eval (train "
        "on every sample, balance validation and test) or none.",
    ),
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
    options = fitting.options(epochs, samples.seed)
    choice = samples.choice(data)
    _check_outputs(out, report)
    stale = (out / CALIBRATION_FILE).is_file()
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
    if stale:
        console.print(
            "the folder's dip_calibration.json, fitted for the DIP this one replaces, was removed: "
            "rerun decoy models fight-threshold (or calibrate) for this one",
            highlight=False,
        )


@app.command("dog")
@with_groups
def dog(
    data: list[Path] = typer.Argument(..., help=DATA_HELP),
    out: Path = typer.Option(DEFAULT_OUT, "--out", help="Model folder to write dog.pt/json in."),
    report: Path | None = typer.Option(None, "--report", help=REPORT_HELP),
    epochs: int = typer.Option(DOG_EPOCHS, "--epochs", help="Most epochs (the paper's)."),
    fitting: Fitting = Fitting(),
    samples: SampleOptions = SampleOptions(),
    damage_weight: float = typer.Option(
        DAMAGE_WEIGHT, "--damage-weight", help="Weight of the damage MSE in the loss."
    ),
    hit_group_weight: float = typer.Option(
        HIT_GROUP_WEIGHT, "--hit-group-weight", help="Weight of the hit-group cross-entropy."
    ),
    kl_weight: float = typer.Option(KL_WEIGHT, "--kl-weight", help="Weight of the KL term."),
    draws: int = typer.Option(DRAWS, "--draws", help=DRAWS_HELP),
    min_cell: int = typer.Option(MIN_CELL, "--min-cell", help=MIN_CELL_HELP),
) -> None:
    """Train DOG, the Damage Outcome Generator (how much damage, which hit group).

    A conditional VAE trained on the damaging samples with early stopping on the validation
    part; test metrics are printed and saved with the model."""
    weights = DogLossWeights(damage=damage_weight, hit_group=hit_group_weight, kl=kl_weight)
    options = fitting.options(epochs, samples.seed)
    choice = samples.choice(data)
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
