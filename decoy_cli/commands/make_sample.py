"""`decoy make-sample`: play scripted rounds in the simulator and write them as a synthetic ESTA
match file (the sample `decoy evaluate` uses when it is given no data)."""

from __future__ import annotations

import time
from pathlib import Path

import typer
from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeElapsedColumn
from rich.table import Table

from decoy_cli.commands._console import make_console
from decoy_cli.commands._options import MAPS_HELP, models_option
from decoy_cli.damage import DEFAULT_MODELS, load_damage_model, parse_models
from decoy_cli.damage.model_maps import map_warnings
from decoy_cli.errors import DecoyError
from decoy_cli.files import check_folder_writable
from decoy_cli.synth import PlayedRound, write_sample
from decoy_cli.synth.sample import MAX_ROUNDS
from decoy_cli.waypoints.build import canonical_map

DEFAULT_OUT = Path("examples") / "sample"


def make_sample(
    out: Path = typer.Option(DEFAULT_OUT, "--out", help="Folder to write the match file to."),
    rounds: int = typer.Option(8, "--rounds", help=f"Rounds to play (1-{MAX_ROUNDS})."),
    seed: int = typer.Option(0, "--seed", help="Seed of every random choice (>= 0)."),
    models: str = models_option(DEFAULT_MODELS),
    map_name: str = typer.Option("dust2", "--map", help=f"The map to play on: {MAPS_HELP}."),
) -> None:
    """Write a synthetic ESTA match: scripted 5v5 rounds played in the simulator.

    Both teams follow plausible routes (on de_dust2 hand-written T strategies such as A long, B
    tunnels or a mid-to-A split; on other maps executes and splits along shortest paths from the
    spawns to the sites; CT setups such as 2-1-2), the bomb rules are on, and combat runs
    through the damage models (none: rounds end by the bomb or time). The file is labelled
    synthetic in its metadata. The same seed and models give the same bytes.
    """
    if not 1 <= rounds <= MAX_ROUNDS:
        raise DecoyError(f"--rounds must be between 1 and {MAX_ROUNDS}, not {rounds}")
    if seed < 0:
        raise DecoyError(f"--seed must be >= 0, not {seed}")
    map_id = canonical_map(map_name)
    console = make_console()
    choice = parse_models(models)
    damage_model = load_damage_model(choice)
    if damage_model is None:
        console.print(
            "no damage models: combat is off (rounds end by bomb or time)", style="yellow"
        )
    for line in map_warnings(choice, [map_id]):
        console.print(f"warning: {line}", style="yellow", markup=False)
    check_folder_writable(out)  # fail before playing, not after
    status = make_console(stderr=True)
    progress = Progress(
        TextColumn("playing rounds"),
        BarColumn(),
        MofNCompleteColumn(),
        TimeElapsedColumn(),
        console=status,
        transient=True,
        disable=not status.is_terminal,  # rich leaves a blank line on a pipe
    )
    started = time.perf_counter()
    with progress:
        task = progress.add_task("rounds", total=rounds)
        path, sample = write_sample(
            out,
            rounds,
            seed,
            damage_model,
            str(choice),
            on_round=lambda _: progress.advance(task),
            map_name=map_id,
        )
    seconds = time.perf_counter() - started

    table = Table(title=f"{sample.match.match_id} (synthetic, damage models: {choice})")
    table.add_column("round", justify="right")
    table.add_column("T plan")
    table.add_column("CT setup")
    table.add_column("buys T/CT")
    table.add_column("outcome", no_wrap=True)
    table.add_column("end (s)", justify="right")
    table.add_column("kills T/CT", justify="right")
    table.add_column("plant", justify="right", no_wrap=True)
    for played in sample.rounds:
        table.add_row(*_row(played))
    console.print(table)
    winners = [r.record.winning_side for r in sample.rounds]
    kills = sum(len(r.record.kills) for r in sample.rounds)
    plants = sum(r.record.bomb_plant_tick is not None for r in sample.rounds)
    console.print(
        f"{len(winners)} rounds (T {winners.count('T')}, CT {winners.count('CT')}), "
        f"{kills} kills, {plants} plants; played and written in {seconds:.1f} s"
    )
    console.print(f"wrote {path} ({path.stat().st_size / 1024:.0f} KiB)")


def _row(played: PlayedRound) -> tuple[str, ...]:
    """One summary row: the plan, the buys, the outcome, kills by side and the plant."""
    record = played.record
    sides = {i: p.side for i, p in enumerate(record.players)}
    t_kills = sum(sides[k.attacker] == "T" for k in record.kills)
    plant = "–"
    for event in record.bomb_events:
        if event.action == "plant":
            at = (event.tick - record.freeze_end_tick) / 128
            plant = f"{event.site} at {at:.0f} s"
    return (
        str(record.round_num),
        played.plan.strategy.name,
        played.plan.ct_setup,
        f"{played.buys.get('T', '?')}/{played.buys.get('CT', '?')}",
        f"{record.winning_side} {record.end_reason}",
        f"{played.end_seconds:.1f}",
        f"{t_kills}/{len(record.kills) - t_kills}",
        plant,
    )
