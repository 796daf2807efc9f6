"""`decoy models evaluate MODEL_FOLDER DATA...`, and the pieces the `train` commands share with
it: reading samples with a progress bar, the metric tables beside the paper's values, and
writing the metrics JSON and figures."""

from __future__ import annotations

import json
import math
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np
import typer
from rich.console import Console
from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn
from rich.table import Table

from decoy_cli.damage.evaluation import DRAWS, PAPER_DIP, PAPER_DOG
from decoy_cli.damage.samples import (
    DEFAULT_WINDOW_S,
    Samples,
    SampleStats,
    balance,
    build_samples,
    split_samples,
)
from decoy_cli.damage.scores import MIN_CELL
from decoy_cli.errors import ModelError
from decoy_cli.files import write_atomic

DEFAULT_EVALUATE_OUT = Path("decoy-out") / "models" / "evaluation"

DATA_HELP = "ESTA match files (.json.xz or .json) or folders of them."
MODE_HELP = (
    "How rounds become samples: auto (frames of both teams -> frames, else events), frames "
    "(the paper's, per frame every enemy pair) or events (events-only proxy for files without "
    "frames)."
)
WINDOW_HELP = "Events mode: seconds within which an event row places a player (negatives)."
SPLIT_HELP = "Split unit: match or round (never single samples)."
SEED_HELP = "Seed of the split, the 1:1 balancing, and (training) weights and shuffling."
VAL_HELP = "Share of the split units for validation (early stopping, DIP threshold)."
TEST_HELP = "Share of the split units held out for the test metrics."
BALANCE_HELP = "DIP: keep all positives and as many random negatives per part (the paper's 1:1)."
DRAWS_HELP = "DOG generative mode: samples drawn per test condition."
MIN_CELL_HELP = "DOG: fewest real samples a (weapon, hit group) cell needs for the Wasserstein."


def load_samples(
    console: Console, data: Sequence[Path], mode: str, window_s: float
) -> tuple[Samples, SampleStats]:
    """Samples from the data files with a progress bar, and a one-line summary."""
    errors = Console(stderr=True)  # drawn only on a terminal: no stray lines in pipes
    progress = Progress(
        TextColumn("reading samples"),
        BarColumn(),
        MofNCompleteColumn(),
        console=errors,
        transient=True,
        disable=not errors.is_terminal,
    )
    with progress:
        task = progress.add_task("files", total=None)

        def advance(_: Path, done: int, total: int) -> None:
            progress.update(task, completed=done, total=total)

        samples, stats = build_samples(data, mode, window_s, on_file=advance)
    excluded = sum(stats.excluded.values())
    console.print(
        f"{len(samples):,} samples ({stats.positives:,} damaging) from {stats.files} files: "
        f"{stats.rounds_frames} rounds in frames mode, {stats.rounds_events} in events mode, "
        f"{stats.rounds_without_samples} without samples, {stats.round_errors} unreadable; "
        f"{excluded} damage rows left out"
        + (
            " (" + ", ".join(f"{n} {why}" for why, n in sorted(stats.excluded.items())) + ")"
            if excluded
            else ""
        )
    )
    return samples, stats


def _number(value: Any, digits: int = 3) -> str:
    if value is None or (isinstance(value, float) and not math.isfinite(value)):
        return "–"
    if isinstance(value, int):
        return f"{value:,}"
    return f"{value:.{digits}f}"


def dip_table(metrics: dict[str, Any], title: str) -> Table:
    """DIP's metrics beside the paper's."""
    table = Table(title=title)
    for column in ("metric", "value", "paper"):
        table.add_column(column, justify="left" if column == "metric" else "right")
    for name in ("accuracy", "precision", "recall", "f1", "roc_auc", "average_precision"):
        table.add_row(name, _number(metrics[name]), _number(PAPER_DIP.get(name)))
    table.add_row("threshold", _number(metrics["threshold"]), _number(PAPER_DIP["threshold"]))
    table.add_row(
        "samples (positive / negative)",
        f"{metrics['positives']:,} / {metrics['negatives']:,}",
        "1:1 balanced",
    )
    return table


def dog_table(metrics: dict[str, Any], title: str) -> Table:
    """DOG's metrics beside the paper's."""
    table = Table(title=title)
    for column in ("metric", "value", "paper"):
        table.add_column(column, justify="left" if column == "metric" else "right")
    rows = (
        ("damage MAE, reconstruction (HP)", "damage_mae_hp", 2),
        ("damage R², reconstruction", "damage_r2", 3),
        ("hit-group accuracy, reconstruction", "hit_group_accuracy", 3),
        ("hit-group accuracy, generative", "hit_group_accuracy_generated", 3),
        ("mean Wasserstein per cell (HP)", "mean_wasserstein_hp", 2),
        ("Wasserstein, all damage (HP)", "wasserstein_all_hp", 2),
        ("mean damage generated / real (HP)", None, 1),
    )
    for label, key, digits in rows:
        if key is None:
            value = (
                f"{metrics['generated_mean_damage_hp']:.1f} / {metrics['real_mean_damage_hp']:.1f}"
            )
            table.add_row(label, value, "–")
            continue
        table.add_row(label, _number(metrics[key], digits), _number(PAPER_DOG.get(key), digits))
    table.add_row(
        "cells in the Wasserstein mean",
        f"{metrics['wasserstein_cells']} (≥ {metrics['min_cell']} real samples)",
        "–",
    )
    table.add_row("damaging samples", f"{metrics['samples']:,}", "–")
    return table


def cells_table(cells: list[dict[str, Any]]) -> Table:
    """The (weapon, hit group) cells of the Wasserstein mean."""
    table = Table(title="generated vs real damage per cell")
    for column in ("weapon", "hit group", "real", "generated", "Wasserstein (HP)"):
        table.add_column(column, justify="left" if column in ("weapon", "hit group") else "right")
    for cell in cells:
        table.add_row(
            cell["weapon"],
            cell["hit_group"],
            f"{cell['real']:,}",
            f"{cell['generated']:,}",
            f"{cell['wasserstein_hp']:.2f}",
        )
    return table


def json_ready(value: Any) -> Any:
    """`value` with NaN and infinities as None and numpy scalars as Python numbers (strict
    JSON has no NaN)."""
    if isinstance(value, float) and not math.isfinite(value):
        return None
    if isinstance(value, dict):
        return {k: json_ready(v) for k, v in value.items()}
    if isinstance(value, list | tuple):
        return [json_ready(v) for v in value]
    if isinstance(value, np.generic):
        return json_ready(value.item())
    return value


def write_json(path: Path, data: dict[str, Any]) -> None:
    """Pretty strict JSON (see `json_ready`), written atomically."""
    write_atomic(path, (json.dumps(json_ready(data), indent=2) + "\n").encode())


def evaluate(
    model_folder: Path = typer.Argument(
        ..., help="A model folder: dip.pt/json and/or dog.pt/json (trained or imported)."
    ),
    data: list[Path] = typer.Argument(..., help=DATA_HELP),
    out: Path = typer.Option(
        DEFAULT_EVALUATE_OUT, "--out", help="Folder for metrics.json and the figures."
    ),
    subset: str = typer.Option(
        "all",
        "--subset",
        help="Samples to evaluate on: all, or the train, val or test part of the split below "
        "(the same options as training give the same parts).",
    ),
    split: str = typer.Option("match", "--split", help=SPLIT_HELP),
    seed: int = typer.Option(0, "--seed", help=SEED_HELP),
    val_fraction: float = typer.Option(0.15, "--val-fraction", help=VAL_HELP),
    test_fraction: float = typer.Option(0.15, "--test-fraction", help=TEST_HELP),
    mode: str = typer.Option("auto", "--mode", help=MODE_HELP),
    window: float = typer.Option(DEFAULT_WINDOW_S, "--window", help=WINDOW_HELP),
    balanced: bool = typer.Option(True, "--balance/--no-balance", help=BALANCE_HELP),
    threshold: float | None = typer.Option(
        None, "--threshold", help="DIP decision threshold (default: the model's own)."
    ),
    draws: int = typer.Option(DRAWS, "--draws", help=DRAWS_HELP),
    min_cell: int = typer.Option(MIN_CELL, "--min-cell", help=MIN_CELL_HELP),
) -> None:
    """Evaluate a damage-model folder (trained or imported) on ESTA data.

    Prints DIP's and DOG's metrics beside the paper's and writes metrics.json with the figures:
    ROC and precision-recall curves, reconstructed vs real damage, the error histogram, the
    hit-group confusion matrix, generated vs real damage per weapon and hit group."""
    console = Console()
    if not model_folder.is_dir():
        raise ModelError(f"{model_folder}: no such model folder")
    has_dip = (model_folder / "dip.json").is_file()
    has_dog = (model_folder / "dog.json").is_file()
    if not (has_dip or has_dog):
        raise ModelError(f"{model_folder}: holds neither dip.json nor dog.json")
    if threshold is not None and not 0.0 <= threshold <= 1.0:
        raise ModelError(f"--threshold must be a probability in [0, 1], not {threshold}")
    if draws < 1 or min_cell < 1:
        raise ModelError("--draws and --min-cell must be at least 1")
    samples, stats = load_samples(console, data, mode, window)
    if subset == "all":
        index = np.arange(len(samples))
    else:
        parts = split_samples(samples, split, seed, val_fraction, test_fraction)
        index = parts.part(subset)
    from decoy_cli.damage.evaluation import evaluate_dip, evaluate_dog
    from decoy_cli.damage.evaluation_figures import write_dip_figures, write_dog_figures
    from decoy_cli.damage.model_folder import load_dip, load_dog

    report: dict[str, Any] = {
        "model_folder": str(model_folder),
        "data": [str(d) for d in data],
        "subset": subset,
        "split": None if subset == "all" else {"by": split, "seed": seed},
        "mode": mode,
        "window_s": window,
        "sample_stats": stats.to_json(),
    }
    figures: list[Path] = []
    name = model_folder.name or str(model_folder)
    if has_dip:
        dip = load_dip(model_folder)
        chosen = balance(samples, index, seed) if balanced else index
        if not samples.hit[chosen].any():
            raise ModelError(f"no damaging samples in the {subset} samples: DIP cannot be scored")
        result = evaluate_dip(dip, samples.take(chosen), threshold)
        report["dip"] = {"balanced": balanced, **result.metrics}
        console.print(dip_table(result.metrics, f"DIP of {name} ({subset} samples)"))
        figures += write_dip_figures(result, out, f"DIP of {name}")
    if has_dog:
        dog = load_dog(model_folder)
        chosen = index[samples.hit[index]]
        if len(chosen) == 0:
            raise ModelError(f"no damaging samples in the {subset} samples: DOG cannot be scored")
        result = evaluate_dog(dog, samples.take(chosen), seed, draws, min_cell)
        report["dog"] = result.metrics
        console.print(dog_table(result.metrics, f"DOG of {name} ({subset} samples)"))
        if result.metrics["cells"]:
            console.print(cells_table(result.metrics["cells"]))
        figures += write_dog_figures(result, out, f"DOG of {name}")
    write_json(out / "metrics.json", report)
    console.print(f"metrics and {len(figures)} figures written to {out}")
