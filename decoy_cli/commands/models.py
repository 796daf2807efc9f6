"""`decoy models ...`: damage models (DIP and DOG). `import-decoy` imports the paper's."""

from __future__ import annotations

from pathlib import Path

import typer
from rich.console import Console
from rich.table import Table

from decoy_cli.commands.model_evaluation import evaluate

DEFAULT_IMPORT_OUT = Path("decoy-out") / "models" / "paper"

app = typer.Typer(
    help="Damage models (DIP and DOG): import the DECOY paper's checkpoints, evaluate a model.",
    no_args_is_help=True,
)


@app.command("import-decoy")
def import_decoy(
    path: Path = typer.Argument(
        ...,
        help="Folder with the paper's dip_best_model.pth and dog_best_model.pth "
        "(and, optionally checked, dip_args.json and dog_args.json) from HATS-ICT/decoy.",
    ),
    out: Path = typer.Option(
        DEFAULT_IMPORT_OUT, "--out", help="Model folder to write (dip.pt/json, dog.pt/json)."
    ),
) -> None:
    """Import the DECOY paper's published DIP and DOG into a model folder for --models.

    The weights load unchanged into the project's networks, except DOG's hit groups, permuted
    from the paper's order (Head, Neck, Stomach, Chest, Arm, Leg) to the project's (Head, Neck,
    Chest, Stomach, Arm, Leg). Features are the paper's raw Hammer units; DIP threshold 0.444.
    """
    from decoy_cli.damage.paper import import_paper

    result = import_paper(path, out)
    console = Console()
    table = Table(title="imported DECOY checkpoints")
    for column in ("model", "file", "epoch", "best val loss", "parameters"):
        table.add_column(column, justify="right" if column in ("epoch", "parameters") else "left")
    for model in result.models:
        table.add_row(
            model.kind.upper(),
            model.source.name,
            "–" if model.epoch is None else str(model.epoch),
            "–" if model.best_val_loss is None else f"{model.best_val_loss:.4f}",
            f"{model.parameters:,}",
        )
    console.print(table)
    console.print(
        f"DIP threshold {result.threshold}, Hammer-unit features; model folder written to "
        f"{result.folder}\nuse it with: decoy replay FILE:ROUND --models {result.folder}"
    )


app.command("evaluate")(evaluate)
