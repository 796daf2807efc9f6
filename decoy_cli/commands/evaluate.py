"""`decoy evaluate`: replay many rounds in parallel and report how faithful the replay is."""

from __future__ import annotations

import time
from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING

import typer
from rich.console import Console
from rich.progress import (
    BarColumn,
    MofNCompleteColumn,
    Progress,
    TaskID,
    TextColumn,
    TimeElapsedColumn,
    TimeRemainingColumn,
)
from rich.table import Table
from rich.text import Text

from decoy_cli.bench.machine import machine_line, usable_cores
from decoy_cli.commands._console import make_console
from decoy_cli.commands._groups import with_groups
from decoy_cli.commands._options import MAPS_HELP, RunOptions, world_option
from decoy_cli.damage import parse_models
from decoy_cli.damage.model_maps import map_warnings
from decoy_cli.errors import DecoyError
from decoy_cli.esta import collect_match_files
from decoy_cli.evaluate.bomb_report import BOMB_HEADER, bomb_rows
from decoy_cli.evaluate.markdown import interval, num
from decoy_cli.evaluate.outputs import output_lock, write_outputs
from decoy_cli.evaluate.report import (
    RunInfo,
    combat_caveats,
    command_line,
    data_kind,
    mechanics,
    protocols,
    table_groups,
    world_line,
)
from decoy_cli.evaluate.runner import (
    DEFAULT_ROUND_TIMEOUT_S,
    Evaluation,
    ProgressEvent,
    default_inputs,
    make_settings,
    run_evaluation,
)
from decoy_cli.evaluate.tables import Tables, build_tables
from decoy_cli.metrics import PAPER_PROTOCOL_NAMES, BombMetrics
from decoy_cli.waypoints.build import GameWorld

if TYPE_CHECKING:
    from decoy_cli.evaluate.backends import DaskBackend, InProcessBackend, LocalBackend

DEFAULT_OUT = Path("decoy-out") / "evaluate"


@with_groups
def evaluate(
    inputs: list[Path] = typer.Argument(
        None,
        metavar="FILE|FOLDER",
        show_default=False,
        help="ESTA match files (.json.xz, .json) and folders of them. Default: the synthetic "
        "sample shipped in examples/sample.",
    ),
    map_name: str = typer.Option(
        "dust2",
        "--map",
        help=f"The map to evaluate ({MAPS_HELP}); files of other maps are skipped.",
    ),
    graph: Path | None = typer.Option(
        None,
        "--graph",
        help="Waypoint graph (.npz from build-waypoints, e.g. with --learn-patches) to replay "
        "on, with the world it was built on; its map must be --map. Default: the shipped one.",
    ),
    world: GameWorld = world_option(),
    sample: int | None = typer.Option(
        None, "--sample", min=1, help="Evaluate a random sample of N rounds (see --seed)."
    ),
    run_options: RunOptions = RunOptions(),
    out: Path = typer.Option(
        DEFAULT_OUT,
        "--out",
        help="Output folder: tables, figures, report.md, and the cache that lets an "
        "interrupted run resume.",
    ),
    round_timeout: float = typer.Option(
        DEFAULT_ROUND_TIMEOUT_S,
        "--round-timeout",
        min=0,
        help="Wall-clock seconds one round may take before it is recorded as a timeout "
        "failure (0: no limit; not on a Dask cluster).",
    ),
    fastdtw: bool | None = typer.Option(
        None,
        "--fastdtw/--no-fastdtw",
        show_default=False,
        help="Also compute paper_dtw_fastdtw, the paper's DTW as its code computed it (the "
        "fastdtw package, radius 1), beside the exact paper_dtw. Slow (pure Python). Default: "
        "on for the paper's Table 2 setting (--no-combat --no-bomb), off otherwise. Part of "
        "the cache key: switching it replays the rounds again.",
    ),
    workers: int | None = typer.Option(
        None,
        "--workers",
        min=0,
        envvar="DECOY_WORKERS",
        show_default=False,
        help="Local worker processes (default: the number of cores). 0: the rounds run in this "
        "process, one after another: no process to start, the quickest for a few rounds, but a "
        "round that crashes the interpreter ends the run (the finished rounds stay cached).",
    ),
    view: bool = typer.Option(
        True,
        "--view/--no-view",
        help="Write view.html beside report.md: one page to look at any round, real against "
        "replay (`decoy view`).",
    ),
    figures: bool = typer.Option(
        True,
        "--figures/--no-figures",
        help="Draw the figures (figures/*.png, shown in report.md); --no-figures leaves them "
        "out, which saves seconds a run when many runs only need the tables.",
    ),
    scheduler: str | None = typer.Option(
        None,
        "--scheduler",
        help="Run the rounds on a running dask.distributed cluster at this address (e.g. "
        "tcp://10.0.0.5:8786) instead of local processes; needs the dask extra, and the "
        "workers must read the input files at the same paths.",
    ),
) -> None:
    """Replay many rounds in parallel and report how faithful the replay is.

    Every round (or a sample) of the ESTA match files runs in worker processes; the results
    are trajectory metrics (both protocols, next to the paper's Table 2), HP, death times,
    outcomes, heatmaps and a report. Finished rounds are cached in the output folder, so
    rerunning an interrupted run resumes it. Exits non-zero when a file or round failed
    (failures.csv says why).
    """
    console = make_console()
    inputs = inputs or default_inputs()
    collect_match_files(inputs)  # bad paths fail here, before a damage model is loaded
    given = run_options
    settings = make_settings(
        map_name=map_name,
        combat=given.combat,
        bomb=given.bomb,
        models=parse_models(given.models),
        mover=given.mover,
        seed=given.seed,
        implausible=given.implausible,
        rate=given.rate,
        deaths=given.deaths,
        missing=given.missing,
        fastdtw=fastdtw,
        graph=graph,
        sight_mesh=given.sight_mesh,
        world=world,
    )
    command = command_line(inputs, settings, sample, out)
    backend: DaskBackend | LocalBackend | InProcessBackend
    if scheduler:
        from decoy_cli.evaluate.backends import DaskBackend

        backend = DaskBackend(scheduler)
        where = f"Dask scheduler {scheduler}"
    elif workers == 0:
        from decoy_cli.evaluate.backends import InProcessBackend

        backend = InProcessBackend()
        where = "this process"
    else:
        from decoy_cli.evaluate.backends import LocalBackend

        count = workers or usable_cores()
        backend = LocalBackend(count)
        where = f"{count} local worker process{'es' if count > 1 else ''}"
    info = RunInfo(command=command, backend=where, sample=sample, machine=machine_line())
    console.print(f"evaluating with {where}: {mechanics(settings)}", highlight=False)
    console.print(f"world: {world_line(settings)}", highlight=False)
    if settings.combat:
        for line in map_warnings(settings.models, [settings.map_name]):
            console.print(f"warning: {line}", style="yellow", markup=False)
    with output_lock(out):
        try:
            with backend, _ProgressDisplay() as on_progress:
                evaluation = run_evaluation(
                    inputs,
                    settings,
                    out,
                    backend,
                    sample=sample,
                    on_progress=on_progress,
                    round_timeout_s=round_timeout or None,
                )
            started = time.perf_counter()
            tables = build_tables(evaluation.accumulator)
            write_outputs(evaluation, tables, out, info, view=view, figures=figures)
        except KeyboardInterrupt:
            console.print(
                f"interrupted: the finished rounds are cached in {out / 'cache'}; run the "
                "same command again to resume",
                style="yellow",
                soft_wrap=True,  # one line, whatever the terminal's width
            )
            raise typer.Exit(130) from None
    try:
        _show(console, evaluation, tables)
        console.print(
            f"outputs written to {out} (report: {out / 'report.md'}"
            + (f", rounds to look at: {out / 'view.html'}" if view else "")
            + f") in {time.perf_counter() - started:.1f} s",
            highlight=False,
        )
    except KeyboardInterrupt:  # the outputs are complete: only the summary is cut short
        raise typer.Exit(130) from None
    if evaluation.failures:
        raise DecoyError(
            f"{len(evaluation.failures)} files or rounds failed "
            f"({evaluation.accumulator.rounds} rounds evaluated); see {out / 'failures.csv'}"
        )


class _ProgressDisplay:
    """A rich progress display on stderr with one bar per stage (files indexed, rounds)."""

    def __init__(self) -> None:
        stderr = make_console(stderr=True)
        self.progress = Progress(
            TextColumn("{task.description}"),
            BarColumn(),
            MofNCompleteColumn(),
            TextColumn("{task.fields[failed]} failed"),
            TextColumn("{task.fields[rate]}"),
            TimeElapsedColumn(),
            TextColumn("ETA"),
            TimeRemainingColumn(),
            console=stderr,
            transient=True,
            disable=not stderr.is_terminal,
        )
        self.tasks: dict[str, TaskID] = {}
        self.started: dict[str, float] = {}

    def __enter__(self) -> Callable[[ProgressEvent], None]:
        self.progress.start()
        return self.update

    def __exit__(self, *exc: object) -> None:
        self.progress.stop()

    def update(self, event: ProgressEvent) -> None:
        if event.stage not in self.tasks:
            label = "indexing files" if event.stage == "index" else "evaluating rounds"
            self.tasks[event.stage] = self.progress.add_task(
                label, total=event.total, failed=0, rate=""
            )
            self.started[event.stage] = time.perf_counter()
        elapsed = time.perf_counter() - self.started[event.stage]
        unit = "files" if event.stage == "index" else "rounds"
        rate = f"{event.done / elapsed:.2f} {unit}/s" if event.done and elapsed > 0 else ""
        self.progress.update(
            self.tasks[event.stage], completed=event.done, failed=event.failed, rate=rate
        )


def _show(console: Console, evaluation: Evaluation, tables: Tables) -> None:
    """The run's counts, the trajectory tables, HP/deaths/outcomes, places and failures."""
    kind = data_kind(evaluation)
    if kind in ("synthetic", "mixed"):
        console.print(
            Text.assemble(
                (f"data: {kind}", "bold yellow"),
                " (generated by the project, not recorded in real matches): these numbers "
                "check the pipeline, not reality",
            )
        )
    else:
        console.print(f"data: {kind}")
    computed = f"{evaluation.computed} computed"
    if evaluation.computed:
        rate = evaluation.computed / evaluation.compute_seconds
        computed += f" in {evaluation.compute_seconds:.1f} s, {rate:.2f} rounds/s"
    console.print(
        f"{evaluation.accumulator.rounds} rounds evaluated ({computed}; {evaluation.cached} "
        f"from the cache), {len(tables.players)} player-rounds, {len(evaluation.failures)} "
        f"failures; {mechanics(evaluation.settings)}",
        highlight=False,
    )
    if tables.rounds_with_warnings:
        console.print(
            f"{tables.rounds_with_warnings} rounds replayed with implausible data "
            "(--implausible warn; their warnings are in rounds.csv and report.md)",
            style="yellow",
        )
    if tables.rounds_with_contradictions:
        console.print(
            f"{tables.rounds_with_contradictions} rounds whose frames and events contradict "
            "each other, replayed (rounds.csv: contradictions; report.md)",
            style="yellow",
        )
    if tables.rounds_with_inferred:
        console.print(
            f"{tables.rounds_with_inferred} rounds lack fields the game needs (weapons, armour, "
            "the bomb's carrier, the defuser): filled by rule, named in rounds.csv (inferred) "
            "and report.md",
            style="yellow",
        )
    groups = table_groups(tables)
    stats = tables.trajectory.set_index(["metric", "group"])
    titles = {
        "clock": "protocol clock (m): mean ± std, [95% interval of the mean, by round], "
        "median · p90",
        "paper": "protocol paper (m): mean ± std, [95% interval of the mean], (the paper's "
        "Table 2)",
    }
    for protocol, names in protocols(tables):
        console.print(titles[protocol], style="italic", highlight=False)
        table = Table()
        table.add_column("metric", no_wrap=True)
        for group in groups:
            table.add_column(group, justify="right", no_wrap=True)
        for name in names:
            cells = []
            for group in groups:
                row = stats.loc[(name, group)]
                if name in PAPER_PROTOCOL_NAMES:
                    detail = f"({num(row['paper_mean'])} ± {num(row['paper_std'])})"
                else:
                    detail = f"{num(row['median'])} · {num(row['p90'])}"
                mean = f"{num(row['mean'])} ± {num(row['std'])}"
                ci = interval(row["mean_low"], row["mean_high"])
                cells.append(
                    Text.assemble(f"{mean}\n", (f"{ci}\n" if ci else "", "dim"), (detail, "dim"))
                )
            table.add_row(name, *cells)
        console.print(table)
    for row in tables.summary.unevaluated.itertuples():
        console.print(f"  {row.group}: {row.count} not evaluated ({row.reason})", highlight=False)
    caveats = combat_caveats(tables, evaluation.settings)
    combat = Table(title="HP, deaths and outcomes", caption=" ".join(caveats) or None)
    for column in ("metric", "value", "95% interval", "n", "paper", "over / why not"):
        combat.add_column(column, justify="right" if column in ("value", "n", "paper") else "left")
    for row in tables.combat.itertuples():
        combat.add_row(
            row.metric,
            num(row.value),
            interval(row.low, row.high),
            str(row.n),
            num(row.paper),
            str(row.note),
        )
    console.print(combat)
    if tables.outcome is not None:
        matrix = tables.outcome.winner_confusion
        console.print("winner: data (rows) against replay (columns)")
        confusion = Table()
        confusion.add_column("")
        for column in matrix.columns:
            confusion.add_column(str(column), justify="right")
        for label in matrix.index:
            confusion.add_row(str(label), *map(str, matrix.loc[label]))
        console.print(confusion)
    if tables.bomb is not None:
        _show_bomb(console, tables.bomb)
    places = Table(title="where the replay is off most (nav places, by the player's place)")
    for column in ("place", "original", "replay", "diff (pp)", "distance (m)", "off graph"):
        places.add_column(column, justify="left" if column == "place" else "right")
    for row in tables.places.head(6).itertuples():
        places.add_row(
            str(row.place),
            f"{100 * row.original_share:.1f}%",
            f"{100 * row.replay_share:.1f}%",
            f"{row.difference_pp:+.2f}",
            num(row.mean_error_m, 2),
            f"{100 * row.off_graph_share:.1f}%",
        )
    console.print(places)
    for failure in evaluation.failures[:10]:
        where = failure.where
        console.print(
            Text.assemble((failure.kind, "red"), f" {where}: {failure.message}"), highlight=False
        )
    if len(evaluation.failures) > 10:
        console.print(f"… {len(evaluation.failures) - 10} more in failures.csv")


def _show_bomb(console: Console, bomb: BombMetrics) -> None:
    """The bomb table and the plant confusion (report.md has the defuse confusion too)."""
    matrix = bomb.plant_confusion
    planted = " · ".join(
        f"{d} / {r}: {matrix.loc[d, r]}" for d in matrix.index for r in matrix.columns
    )
    caption = f"plants, data / replay: {planted}"
    if bomb.anomalies:
        caption += f"; {bomb.anomalies} rounds with anomalies in their bomb data (report.md)"
    table = Table(title=f"the bomb ({bomb.n_rounds} rounds with bomb data)", caption=caption)
    for column in BOMB_HEADER:
        table.add_column(column, justify="right" if column in ("value", "rounds") else "left")
    for row in bomb_rows(bomb):
        table.add_row(*row)
    console.print(table)
