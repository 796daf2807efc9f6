"""`decoy models ...`: damage models (DIP and DOG). `import-decoy` imports the paper's,
`evaluate` scores a model folder on ESTA data (decoy_cli/modeling/folder_evaluation.py)."""

from __future__ import annotations

from pathlib import Path

import typer
from rich.console import Console
from rich.table import Table

from decoy_cli.commands._console import make_console
from decoy_cli.commands._damage_output import (
    BALANCE_HELP,
    DATA_HELP,
    DRAWS_HELP,
    MIN_CELL_HELP,
    cells_table,
    dip_table,
    dog_table,
    hp_lost_table,
    print_samples,
    progress_bars,
)
from decoy_cli.commands._groups import with_groups
from decoy_cli.commands._options import SampleOptions, world_option
from decoy_cli.damage import CHOICES_HELP, PAPER_FOLDER, parse_models
from decoy_cli.damage.calibration import Calibration, CalibrationKind, Decision
from decoy_cli.damage.choice import MODELS_METAVAR
from decoy_cli.errors import DecoyError
from decoy_cli.files import check_folder_writable
from decoy_cli.modeling.calibration_fit import MIN_RECALL
from decoy_cli.modeling.folder_evaluation import BALANCED, DEFAULT_SUBSET, evaluate_model_folder
from decoy_cli.modeling.network_evaluation import DRAWS
from decoy_cli.modeling.paper_download import PAPER_BASE_URL, PAPER_COMMIT, PAPER_REPOSITORY
from decoy_cli.modeling.scores import MIN_CELL
from decoy_cli.modeling.split import SplitPart
from decoy_cli.waypoints.build import GameWorld

DEFAULT_IMPORT_OUT = PAPER_FOLDER
DEFAULT_EVALUATE_OUT = Path("decoy-out") / "models" / "evaluation"

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
    from decoy_cli.modeling.paper_import import import_paper

    check_folder_writable(out)  # before the checkpoints are read and converted
    result = import_paper(path, out)
    console = make_console()
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


@app.command("download-decoy")
def download_decoy(
    out: Path = typer.Option(
        DEFAULT_IMPORT_OUT, "--out", help="Model folder to write (dip.pt/json, dog.pt/json)."
    ),
    base_url: str = typer.Option(
        PAPER_BASE_URL, "--base-url", help="Where the repository's files are served (a mirror)."
    ),
    timeout: float = typer.Option(60.0, "--timeout", min=1.0, help="Seconds to wait for data."),
) -> None:
    """Download the DECOY paper's published DIP and DOG (HATS-ICT/decoy at a fixed commit),
    check every file's SHA-256, and import them into a model folder for --models (as
    import-decoy does). The downloaded files are kept in OUT/checkpoints."""
    from decoy_cli.modeling.paper_download import download_paper_files
    from decoy_cli.modeling.paper_import import import_paper

    check_folder_writable(out)
    files = download_paper_files(out / "checkpoints", base_url, timeout)
    result = import_paper(out / "checkpoints", out)
    make_console().print(
        f"{len(files)} files of {PAPER_REPOSITORY}@{PAPER_COMMIT[:7]} verified; model folder "
        f"written to {result.folder}\nuse it with: decoy replay FILE:ROUND --models "
        f"{result.folder}",
        highlight=False,
    )


@app.command("fit-rules")
def fit_rules_command(
    model_folder: Path = typer.Argument(..., help="A model folder with the DIP to pair with."),
    data: list[Path] = typer.Argument(..., help=DATA_HELP),
) -> None:
    """Learn the parts of the rules-grounded damage model from real hits (where shots land, by
    weapon and distance; how many land in one 0.5 s step, by weapon) and write rules.json
    into a folder that holds a DIP and no DOG: `--models FOLDER` then damages by the game's
    rules. (A folder with a DOG keeps damaging by its DOG: copy its dip.* to a new folder.)"""
    from decoy_cli.esta import collect_match_files, read_match
    from decoy_cli.modeling.rules_fit import fit_rules

    if not (model_folder / "dip.json").is_file():
        raise DecoyError(f"{model_folder}: holds no dip.json to pair the rules with")
    if (model_folder / "dog.json").is_file():
        raise DecoyError(
            f"{model_folder}: holds a DOG, which --models would use instead of the rules; "
            "copy dip.pt and dip.json to a folder of their own and fit the rules there"
        )
    check_folder_writable(model_folder)
    files, _ = collect_match_files(data)
    rounds = [r for f in files for r in read_match(f).rounds]
    rules = fit_rules(rounds)
    rules.provenance["data"] = [f.name for f in files]
    path = rules.save(model_folder)
    make_console().print(
        f"rules fitted on {rules.provenance['rounds']} rounds of "
        f"{', '.join(sorted({r.map_name for r in rounds}))}: hit groups from "
        f"{rules.provenance['hits']} firearm hits with their hit group and raw damage and "
        f"{rules.provenance['hits_by_hp_lost']} whose HP lost the rules explain (left out: "
        f"{rules.provenance['hits_unexplained']} they do not), penetration from the former, "
        f"bullets per step from {rules.provenance['steps']} damaging steps; written to {path}",
        highlight=False,
    )


@app.command("fight-threshold")
def fight_threshold_command(
    model_folder: Path = typer.Argument(..., help="A model folder with dip.pt/json."),
    data: list[Path] = typer.Argument(
        ...,
        help="ESTA files or folders: real rounds whose frames hold both teams, and real damage "
        "events (e.g. ../shared/data/cs2_dust2_both/spirit-vs-falcons-m2-dust2-r01-12.json.xz "
        "../shared/data/esta_dust2_events); a round given twice (at two frame rates) counts twice.",
    ),
    min_recall: float = typer.Option(
        MIN_RECALL,
        "--min-recall",
        min=0.0,
        max=1.0,
        help="Least share of each map's real damaging steps DIP must still call hits (those "
        "it did not train on, where the map has any).",
    ),
    world: GameWorld = world_option(
        "The world whose sight gives the pairs: CS:GO's (csgo) or CS2's (cs2, de_dust2)."
    ),
) -> None:
    """Choose the DIP threshold the simulator's fight decides by, where the fight works: the
    best F1 on real rounds of both teams (a player with one enemy in sight at a frame, both
    aimed as the fight aims; did he lose HP within 1 s?), among the thresholds at which
    DIP still calls --min-recall of every map's real damaging steps hits (those it did not
    train on, where the map has any). Written as the
    folder's dip_calibration.json (kind none); prints every candidate and the choice on each
    half of the rounds (decoy_cli/modeling/fight_threshold.py)."""
    from decoy_cli.damage.model_folder import load_dip, save_calibration
    from decoy_cli.modeling.fight_threshold import choose_for_files
    from decoy_cli.waypoints.build import builtin_graph

    if not (model_folder / "dip.json").is_file():
        raise DecoyError(f"{model_folder}: holds no dip.json to choose a threshold for")
    check_folder_writable(model_folder)
    dip = load_dip(model_folder)
    found = choose_for_files(dip, data, builtin_graph(world=world), min_recall)
    chosen = found.chosen
    table = Table(
        title=f"The fight's threshold: {found.rounds} rounds, {found.pairs} player-frames"
    )
    for column in ("threshold", "F1 in sight", *(f"recall {m}" for m in found.maps), ""):
        table.add_column(column, justify="right")
    for row in chosen.rows:
        mark = ["chosen"] if row["threshold"] == chosen.threshold else []
        mark += ["DIP's own"] if row["threshold"] == chosen.own_threshold else []
        mark += [] if row["allowed"] else ["recall too low"]
        recalls = (f"{row[f'recall:{m}']:.3f}" for m in found.maps)
        table.add_row(f"{row['threshold']:.3f}", f"{row['f1']:.3f}", *recalls, ", ".join(mark))
    console = make_console()
    console.print(table)
    path = save_calibration(model_folder, Calibration("none", 1.0, 0.0, chosen.threshold))
    _say_replaced(console, dip.calibration)
    console.print(
        f"{found.lost_share:.1%} of the player-frames lost HP; chosen on each half of the rounds "
        f"alone: {found.halves[0]:.3f}, {found.halves[1]:.3f}; {len(found.failures)} rounds "
        f"unreadable; the fight decides at {chosen.threshold:.3f}; written to {path}",
        highlight=False,
    )


def _say_replaced(console: Console, before: Calibration | None) -> None:
    """One line naming the calibration a command wrote over, if any."""
    if before is not None:
        console.print(
            f"replaces the folder's {before.kind} calibration (threshold {before.threshold:.3f}), "
            f"which decided by {before.decision}",
            highlight=False,
        )


@app.command("calibrate")
@with_groups
def calibrate(
    model_folder: Path = typer.Argument(..., help="A model folder with dip.pt/json."),
    data: list[Path] = typer.Argument(..., help=DATA_HELP),
    method: CalibrationKind = typer.Option(
        "platt", "--method", help="platt (two parameters), temperature (one) or none."
    ),
    decision: Decision = typer.Option(
        "threshold",
        "--decision",
        help="How the combat step decides a hit from the calibrated probability: threshold "
        "(the paper's rule) or bernoulli (a hit with that probability).",
    ),
    samples: SampleOptions = SampleOptions(),
) -> None:
    """Calibrate a folder's DIP on the validation part of the split (Platt or temperature
    scaling) and write dip_calibration.json into the folder; prints the Brier score and the
    expected calibration error before and after on the validation and test parts (the same
    split options as training give the same parts)."""
    from decoy_cli.modeling.folder_calibration import calibrate_dip_folder

    if (model_folder / "dip.json").is_file():
        check_folder_writable(model_folder)
    choice = samples.choice(data)
    bars, on_file, _ = progress_bars()
    with bars:
        result = calibrate_dip_folder(
            folder=model_folder, choice=choice, kind=method, decision=decision, on_file=on_file
        )
    console = make_console()
    table = Table(title=f"DIP calibration ({result.calibration.kind}) of {model_folder}")
    columns = ("part", "samples (hits)", "Brier", "Brier after", "ECE", "ECE after", "ECE floor")
    for column in columns:
        table.add_column(column, justify="left" if column == "part" else "right")
    for part, s in result.scores.items():
        table.add_row(
            part,
            f"{s['samples']:.0f} ({s['positives']:.0f})",
            *(
                f"{s[k]:.3f}"
                for k in ("brier", "brier_calibrated", "ece", "ece_calibrated", "ece_floor")
            ),
        )
    console.print(table)
    c = result.calibration
    _say_replaced(console, result.replaced)
    console.print(
        f"p' = sigmoid({c.a:.4f} * logit(p) + {c.b:.4f}); threshold {c.threshold:.3f} on the "
        f"calibrated scale; combat decides by {c.decision}; written to {result.path}",
        highlight=False,
    )
    console.print(
        "ECE floor: what a perfectly calibrated model would show on these samples", highlight=False
    )


@app.command("evaluate")
@with_groups
def evaluate(
    models: str = typer.Argument(
        ..., metavar=MODELS_METAVAR, help=f"The models to score: {CHOICES_HELP}."
    ),
    data: list[Path] = typer.Argument(..., help=DATA_HELP),
    out: Path = typer.Option(
        DEFAULT_EVALUATE_OUT, "--out", help="Folder for metrics.json and the figures."
    ),
    subset: SplitPart = typer.Option(
        DEFAULT_SUBSET,
        "--subset",
        help="Samples to evaluate on: all, or the train, val or test part of the split below "
        "(the same options as training give the same parts).",
    ),
    samples: SampleOptions = SampleOptions(),
    balanced: bool = typer.Option(BALANCED, "--balance/--no-balance", help=BALANCE_HELP),
    threshold: float | None = typer.Option(
        None,
        "--threshold",
        help="DIP decision threshold (default: the one the fight decides by: the folder's "
        "dip_calibration.json, else the DIP's own).",
    ),
    draws: int = typer.Option(DRAWS, "--draws", help=DRAWS_HELP),
    min_cell: int = typer.Option(MIN_CELL, "--min-cell", help=MIN_CELL_HELP),
) -> None:
    """Evaluate any --models choice (rules, shipped, paper or a folder) on ESTA data.

    Prints DIP's and DOG's metrics beside the paper's, and the HP lost drawn by whatever decides
    the damage (DOG or rules) against the real per 0.5 s step and, for the rules, per hit, by
    map and (weapon, distance band) cell with the sampling floor; writes metrics.json with the
    figures: ROC and precision-recall curves, reconstructed vs real damage, the error
    histogram, the hit-group confusion matrix, generated vs real damage per weapon and hit
    group. Exits non-zero, after writing them, when a file or round failed."""
    choice = samples.choice(data)
    check_folder_writable(out)  # before minutes of reading and sampling
    bars, on_file, _ = progress_bars()
    with bars:
        result = evaluate_model_folder(
            models=parse_models(models),
            choice=choice,
            out=out,
            subset=subset,
            balanced=balanced,
            threshold=threshold,
            draws=draws,
            min_cell=min_cell,
            on_file=on_file,
        )
    console = make_console()
    print_samples(console, result.samples, result.stats)
    for line in result.warnings:
        console.print(f"warning: {line}", style="yellow", markup=False)
    if result.dip is not None:
        console.print(dip_table(result.dip.metrics, f"DIP of {result.name} ({subset} samples)"))
        for where, m in result.dip_by_map.items():
            console.print(
                f"DIP on {where} ({result.dip_name}, threshold "
                f"{m['threshold']:.3f}): recall {m['recall']:.3f}, precision "
                f"{m['precision']:.3f}, ROC AUC {m['roc_auc']:.3f} ({m['positives']:,} "
                f"damaging, {m['negatives']:,} not)",
                highlight=False,
            )
    if result.dog is not None:
        console.print(dog_table(result.dog.metrics, f"DOG of {result.name} ({subset} samples)"))
        if result.dog.metrics["cells"]:
            console.print(cells_table(result.dog.metrics["cells"]))
    if result.hp_lost:
        console.print(hp_lost_table(result.hp_lost, f"HP lost, {result.name} against real"))
    for note in result.notes:
        console.print(note, highlight=False)
    console.print(f"metrics and {len(result.figures)} figures written to {result.out}")
    failed = len(result.stats.failures)
    if failed:
        raise DecoyError(
            f"{failed} input{'s' if failed > 1 else ''} failed and "
            f"{'are' if failed > 1 else 'is'} left out of the metrics (listed above)"
        )
