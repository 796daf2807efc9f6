"""What `decoy train` and `decoy models evaluate` print alike (not a command): option help
texts, the progress bars, the samples line, the failed inputs, the metric tables beside the
paper's values."""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Literal

from rich.console import Console
from rich.progress import (
    BarColumn,
    MofNCompleteColumn,
    Progress,
    TaskID,
    TextColumn,
    TimeElapsedColumn,
)
from rich.table import Table

from decoy_cli.commands._console import make_console
from decoy_cli.modeling.hp_lost import HpLostScores
from decoy_cli.modeling.network_evaluation import PAPER_DIP, PAPER_DOG, DogMetrics
from decoy_cli.modeling.sample_set import SampleStats
from decoy_cli.modeling.scores import CellRecord

if TYPE_CHECKING:
    from decoy_cli.modeling.training import Progress as TrainingProgress

DATA_HELP = "ESTA match files (.json.xz or .json) or folders of them."


BALANCE_HELP = "DIP: keep all positives and as many random negatives per part (the paper's 1:1)."
DRAWS_HELP = "DOG generative mode: samples drawn per test condition."
MIN_CELL_HELP = (
    "Fewest real samples a (weapon, hit group or distance band) cell needs for the Wasserstein."
)

FAILURES_SHOWN = 5
"""Failed inputs printed one per line; the rest are counted (all are in the JSON report)."""


def progress_bars() -> tuple[
    Progress, Callable[[Path, int, int], None], Callable[[TrainingProgress], None]
]:
    """Progress bars on stderr, drawn only on a terminal (no stray lines in pipes): one over the
    data files and, once training starts, one over all batches of all epochs; and the two
    callbacks that drive them (`on_file` for reading, `progress` for training)."""
    errors = make_console(stderr=True)
    bars = Progress(
        TextColumn("{task.description}"),
        BarColumn(),
        MofNCompleteColumn(),
        TimeElapsedColumn(),
        console=errors,
        transient=True,
        disable=not errors.is_terminal,
    )
    reading = bars.add_task("reading samples", total=None)
    training: list[TaskID] = []
    state = {"val": "–"}

    def on_file(_: Path, done: int, total: int) -> None:
        bars.update(reading, completed=done, total=total)

    def on_step(step: TrainingProgress) -> None:
        if not training:
            training.append(bars.add_task("training", total=None))
        if step.record is not None:
            state["val"] = f"{step.record.val_loss:.4f}"
        bars.update(
            training[0],
            total=step.epochs * step.batches,
            completed=(step.epoch - 1) * step.batches + step.batch,
            description=f"epoch {step.epoch}/{step.epochs}, validation loss {state['val']}",
        )

    return bars, on_file, on_step


def print_samples(console: Console, samples: int, stats: SampleStats) -> None:
    """One line on the samples read, then the inputs that failed (a count and the first few)."""
    excluded = sum(stats.excluded.values())
    console.print(
        f"{samples:,} samples ({stats.positives:,} damaging) from {stats.files} files: "
        f"{stats.rounds_frames} rounds in frames mode, {stats.rounds_events} in events mode, "
        f"{stats.rounds_without_samples} without samples, {stats.round_errors} failed; "
        f"{excluded} damage rows left out"
        + (
            " (" + ", ".join(f"{n} {why}" for why, n in sorted(stats.excluded.items())) + ")"
            if excluded
            else ""
        )
    )
    if stats.partial:
        console.print(
            "kept with part of their outcome missing: "
            + ", ".join(f"{n} {why}" for why, n in sorted(stats.partial.items())),
            highlight=False,
        )
    failures = stats.failures
    if not failures:
        return
    inputs = "input" if len(failures) == 1 else "inputs"
    console.print(f"left out {len(failures)} failed {inputs}:", highlight=False)
    for failure in failures[:FAILURES_SHOWN]:
        where = Path(failure.file).name
        if failure.round_num is not None:
            where += f" round {failure.round_num}"
        console.print(f"  {where} ({failure.kind}): {failure.message}", markup=False)
    if len(failures) > FAILURES_SHOWN:
        console.print(
            f"  and {len(failures) - FAILURES_SHOWN} more (all in the report's sample_stats)",
            highlight=False,
        )


def _number(value: float | None, digits: int = 3) -> str:
    if value is None or (isinstance(value, float) and not math.isfinite(value)):
        return "–"
    if isinstance(value, int):
        return f"{value:,}"
    return f"{value:.{digits}f}"


def dip_table(metrics: Mapping[str, float], title: str) -> Table:
    """DIP's metrics beside the paper's."""
    table = Table(title=title)
    for column in ("metric", "value", "paper"):
        table.add_column(column, justify="left" if column == "metric" else "right")
    for name in ("accuracy", "precision", "recall", "f1", "roc_auc", "average_precision"):
        table.add_row(name, _number(metrics[name]), _number(PAPER_DIP.get(name)))
    table.add_row("threshold", _number(metrics["threshold"]), _number(PAPER_DIP["threshold"]))
    for name, label in (
        ("brier", "Brier score"),
        ("ece", "expected calibration error"),
        ("brier_calibrated", "Brier score, calibrated"),
        ("ece_calibrated", "expected calibration error, calibrated"),
        ("ece_floor", "its floor: a perfectly calibrated model on these samples"),
    ):
        if name in metrics:
            table.add_row(label, _number(metrics[name]), "–")
    table.add_row(
        "samples (positive / negative)",
        f"{metrics['positives']:,} / {metrics['negatives']:,}",
        "1:1 balanced",
    )
    return table


_DogFigure = Literal[
    "damage_mae_hp",
    "damage_r2",
    "hit_group_accuracy",
    "hit_group_accuracy_generated",
    "mean_wasserstein_hp",
    "wasserstein_all_hp",
]


def dog_table(metrics: DogMetrics, title: str) -> Table:
    """DOG's metrics beside the paper's."""
    table = Table(title=title)
    for column in ("metric", "value", "paper"):
        table.add_column(column, justify="left" if column == "metric" else "right")
    rows: tuple[tuple[str, _DogFigure | None, int], ...] = (
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
    for weapon, tv in metrics["hit_group_tv"].items():
        table.add_row(f"hit-group total variation, {weapon}", _number(tv, 3), "–")
    return table


def cells_table(cells: Sequence[CellRecord]) -> Table:
    """The (weapon, hit group) cells of the Wasserstein mean."""
    table = Table(title="generated vs real damage per cell")
    for column in ("weapon", "hit group", "real", "generated", "Wasserstein (HP)"):
        table.add_column(column, justify="left" if column in ("weapon", "hit group") else "right")
    for cell in cells:
        table.add_row(
            cell["weapon"],
            cell["part"],
            f"{cell['real']:,}",
            f"{cell['generated']:,}",
            f"{cell['wasserstein_hp']:.2f}",
        )
    return table


def hp_lost_table(scores: dict[str, dict[str, HpLostScores]], title: str) -> Table:
    """HP lost drawn against real, per unit (step, hit) and map (`damage.hp_lost`)."""
    table = Table(title=title)
    columns = ("unit", "map", "n", "real", "drawn", "bias", "W", "max W", "floor", "cells")
    for column in columns:
        table.add_column(column, justify="left" if column in ("unit", "map") else "right")
    for unit, of_map in scores.items():
        for where, s in of_map.items():
            bias = 100.0 * (s.drawn_mean_hp / s.real_mean_hp - 1.0) if s.real_mean_hp else math.nan
            table.add_row(
                unit,
                where,
                f"{s.steps:,}",
                _number(s.real_mean_hp, 1),
                _number(s.drawn_mean_hp, 1),
                "–" if not math.isfinite(bias) else f"{bias:+.1f}%",
                _number(s.mean_wasserstein_hp, 2),
                _number(s.max_wasserstein_hp, 2),
                _number(s.mean_floor_hp, 2),
                str(len(s.cells)),
            )
    table.caption = (
        "mean HP lost (capped by the victim's HP), real and drawn, per 0.5 s step or per hit; "
        "W: mean Wasserstein (HP) per (weapon, distance band) cell with enough samples, max W "
        "the largest; floor: what the model would score were the real samples drawn from it"
    )
    return table
