"""`decoy snap`: snap ESTA rounds to the waypoint graph and show what their plans ask for."""

from __future__ import annotations

from pathlib import Path

import typer
from rich.console import Console
from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeElapsedColumn

from decoy_cli.commands._console import make_console
from decoy_cli.commands._options import MAPS_HELP, RATE_HELP, world_option
from decoy_cli.commands._snap_output import (
    show_actions,
    show_places,
    show_round,
    show_round_metrics,
    show_summary,
    show_worst,
    totals_table,
)
from decoy_cli.csgo import MAP_NAMES
from decoy_cli.errors import DecoyError, EstaError
from decoy_cli.esta import Round, iter_match_files, parse_round_address, read_match
from decoy_cli.files import write_csv
from decoy_cli.replay import DEFAULT_MAX_SNAP_M
from decoy_cli.replay.plot import plot_round_plan
from decoy_cli.replay.snapping import WITHIN_M
from decoy_cli.replay.study import (
    check_map,
    infeasible_by_place,
    study_files,
    study_round,
)
from decoy_cli.sim.setup import RoundSetup
from decoy_cli.waypoints.build import GameWorld, canonical_map, chosen_graph
from decoy_cli.waypoints.graph import WaypointGraph
from decoy_cli.world.navmesh import load_navmesh

_WITHIN = f"within_{WITHIN_M:g}m"


def snap(
    target: str = typer.Argument(
        ...,
        metavar="FILE:ROUND | FILE | FOLDER",
        help="One round (match.json.xz:3), every round of a match file, or of a folder of them.",
    ),
    map_name: str = typer.Option(
        "dust2",
        "--map",
        help=f"The map whose built-in graph to snap to ({MAPS_HELP}); other maps' files fail.",
    ),
    graph_file: Path | None = typer.Option(
        None, "--graph", help="Waypoint graph (.npz from build-waypoints; overrides --map)."
    ),
    world: GameWorld = world_option(),
    max_snap: float = typer.Option(
        DEFAULT_MAX_SNAP_M,
        "--max-snap",
        min=0.1,
        help="Farthest a position may lie from its waypoint (m, 3-D) and still snap.",
    ),
    metrics: bool = typer.Option(
        False,
        "--metrics",
        help="Fidelity metrics (both protocols) of the snapped-waypoint trajectory against the "
        "original: a first bound on what a perfect replay on this graph can reach.",
    ),
    worst: int = typer.Option(
        10, "--worst", min=0, help="Show this many intervals with the largest speed ratio."
    ),
    csv: Path | None = typer.Option(
        None, "--csv", help="Write one row per player-round (summary and metrics) to this CSV."
    ),
    plot: Path | None = typer.Option(
        None, "--plot", help="FILE:ROUND only: write a PNG of positions, waypoints and paths."
    ),
    actions: int = typer.Option(
        0, "--actions", min=0, help="FILE:ROUND only: print the first N actions of each plan."
    ),
    players: list[str] = typer.Option(
        [], "--player", help="FILE:ROUND only: plot and list only this player (repeatable)."
    ),
    frames: str | None = typer.Option(
        None, "--frames", help="FILE:ROUND only: plot only data frames FIRST:LAST (inclusive)."
    ),
    rate: float | None = typer.Option(None, "--rate", help=RATE_HELP, min=0.1, max=128),
) -> None:
    """Snap rounds to waypoints: snap errors, plan feasibility, the snapped trajectory's fidelity.

    With --metrics, the metrics of the snapped trajectory against the original (the bound a
    replay can reach). Exits non-zero when a file or round failed."""
    console = make_console()
    map_id = canonical_map(map_name)
    path = Path(target)
    graph = chosen_graph(map_id, world, graph_file)
    if path.exists():
        for option, given in (
            ("--plot", plot is not None),
            ("--actions", actions > 0),
            ("--player", bool(players)),
            ("--frames", frames is not None),
        ):
            if given:
                raise typer.BadParameter(f"{option} needs one round (FILE:ROUND)")
        _snap_batch(console, path, graph, max_snap, metrics, worst, csv, rate)
        return
    try:
        file, num = parse_round_address(target)
    except EstaError:
        raise EstaError(f"{target}: no such file or folder") from None
    match = read_match(file, rate=rate)
    check_map(match, graph)
    round_ = match.round(num)
    chosen = _player_rows(round_, players)
    window = _frame_window(frames, round_.num_frames)
    console.print(f"world: {graph.world_source}", highlight=False)
    with RoundSetup(graph=graph).open_physics() as physics:  # the replay's in-the-air rule
        study = study_round(round_, graph, metrics=metrics, max_distance=max_snap, physics=physics)
    show_round(console, round_, study, graph, worst)
    if metrics:
        show_round_metrics(console, study.rows)
    if actions:
        show_actions(console, round_, study, chosen, actions)
    if plot is not None:
        graph_map = str(graph.meta.get("map", ""))
        nav = load_navmesh(graph_map) if graph_map in MAP_NAMES else None
        plot_round_plan(
            study.plan,
            round_.position,
            graph,
            plot,
            nav=nav,
            players=chosen,
            frames=window,
            title=f"{round_.match_id} round {round_.round_num}",
        )
        console.print(f"plot written to {plot}")
    if csv is not None:
        write_csv(csv, study.rows)
        console.print(f"{len(study.rows)} player rows written to {csv}")


def _snap_batch(
    console: Console,
    path: Path,
    graph: WaypointGraph,
    max_snap: float,
    metrics: bool,
    worst: int,
    csv: Path | None,
    rate: float | None,
) -> None:
    """Every round of a file or folder: aggregate table, worst intervals, metrics, failures."""
    files = iter_match_files(path)
    stderr = make_console(stderr=True)
    progress = Progress(
        TextColumn("snapping"),
        BarColumn(),
        MofNCompleteColumn(),
        TextColumn("files, {task.fields[rounds]} rounds"),
        TimeElapsedColumn(),
        console=stderr,
        transient=True,
        disable=not stderr.is_terminal,
    )
    with progress, RoundSetup(graph=graph).open_physics() as physics:
        task = progress.add_task("snap", total=len(files), rounds=0)

        def on_progress(files_done: float, rounds: int) -> None:
            progress.update(task, completed=files_done, rounds=rounds)

        study = study_files(
            files,
            graph,
            metrics=metrics,
            max_distance=max_snap,
            on_progress=on_progress,
            physics=physics,  # the replay's in-the-air rule
            rate=rate,
        )
    if path.is_file() and study.failures and study.failures[0].round_num is None:
        raise EstaError(study.failures[0].message)

    console.print(f"world: {graph.world_source}", highlight=False)
    console.print(totals_table(study.totals, f"{path}: {len(files)} match files"))
    if worst:
        show_worst(console, study.worst(worst), with_match=True)
        show_places(console, infeasible_by_place(study.intervals, worst))
    if metrics:
        show_summary(console, study)
    if csv is not None:
        write_csv(csv, study.rows)
        console.print(f"{len(study.rows)} player-round rows written to {csv}")
    for failure in study.failures:
        console.print(failure.message, style="red", highlight=False)
    if study.failures:
        files_failed = sum(f.round_num is None for f in study.failures)
        rounds_failed = len(study.failures) - files_failed
        raise DecoyError(
            f"{rounds_failed} rounds and {files_failed} files could not be snapped "
            f"({study.totals.rounds} rounds were)"
        )


def _player_rows(round_: Round, names: list[str]) -> list[int]:
    """Row indices of the named players (by name or key), all players when none is named."""
    if not names:
        return list(range(round_.num_players))
    rows: list[int] = []
    for name in names:
        found = [i for i, p in enumerate(round_.players) if name in (p.name, p.key)]
        if not found:
            known = ", ".join(p.name for p in round_.players) or "none"
            raise EstaError(f"round {round_.round_num} has no player {name!r} (players: {known})")
        rows.extend(i for i in found if i not in rows)
    return rows


def _frame_window(text: str | None, num_frames: int) -> tuple[int, int] | None:
    """'FIRST:LAST' as an inclusive frame window inside the round."""
    if text is None:
        return None
    first, colon, last = text.partition(":")
    try:
        window = (int(first), int(last)) if colon else None
    except ValueError:
        window = None
    if window is None or not 0 <= window[0] <= window[1] < num_frames:
        raise typer.BadParameter(
            f"--frames wants FIRST:LAST with 0 ≤ FIRST ≤ LAST < {num_frames}, got {text!r}"
        )
    return window
