"""`decoy replay FILE:ROUND`: replay one real round in the simulator and show how faithful it is."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import typer
from rich.console import Console
from rich.table import Table

from decoy_cli.commands._console import make_console
from decoy_cli.commands._groups import with_groups
from decoy_cli.commands._options import MAPS_HELP, RunOptions, world_option
from decoy_cli.damage import load_damage_model, parse_models
from decoy_cli.damage.model_maps import map_warnings
from decoy_cli.metrics import METRIC_NAMES_CLOCK, METRIC_NAMES_PAPER
from decoy_cli.replay.bomb_fidelity import BombRow
from decoy_cli.replay.replayer import ReplayOptions
from decoy_cli.replay.single import replay_address
from decoy_cli.text import shortened, visible
from decoy_cli.waypoints.build import GameWorld

NOTE_LIMIT = 400
"""Most characters of a note printed (the names in it come from the data)."""


@with_groups
def replay(
    address: str = typer.Argument(..., metavar="FILE:ROUND", help="The round, e.g. m.json.xz:3."),
    run_options: RunOptions = RunOptions(),
    map_name: str | None = typer.Option(
        None,
        "--map",
        help=f"The round's map ({MAPS_HELP}; default: the one the file names); a check.",
    ),
    graph_file: Path | None = typer.Option(
        None,
        "--graph",
        help="Waypoint graph (.npz from build-waypoints; default: the built-in one of the map).",
    ),
    world: GameWorld = world_option(),
    out: Path | None = typer.Option(
        None,
        "--out",
        help="Output folder (default decoy-out/replay/<file name>-<content hash>_r<round>).",
    ),
    gif: bool = typer.Option(False, "--gif", help="Also write an animated GIF of the round."),
) -> None:
    """Replay a real round: snap, plan, simulate at 60 Hz, and compare with the data (with
    --models none, deaths in the data are scripted)."""
    console = make_console()
    given = run_options
    choice = parse_models(given.models)
    damage_model = load_damage_model(choice) if given.combat else None
    if given.combat and damage_model is None:
        console.print(
            "--models none: replaying without shooting (deaths in the data are scripted)",
            style="yellow",
        )
    options = ReplayOptions.of(given, damage_model)
    run = replay_address(
        address,
        options,
        models=str(choice),
        map_name=map_name,
        graph_file=graph_file,
        out=out,
        gif=gif,
        sight_mesh=given.sight_mesh,
        world=world,
    )
    round_, result, players = run.round_, run.result, run.players
    real = (round_.winning_side, round_.end_reason)
    simulated = (result.outcome.winner, result.outcome.reason) if result.outcome else (None, None)
    console.print(
        f"round {round_.round_num} of {round_.match_id}: {round_.num_frames} frames "
        f"({run.summary['frame_rate']}) replayed in "
        f"{run.seconds:.2f} s ({options.mover} mover, combat {'on' if options.combat else 'off'}, "
        f"bomb {'on' if options.bomb else 'off'})"
    )
    console.print(f"world: {run.summary['world']}", highlight=False)
    outcome = Table(title="outcome")
    outcome.add_column("")
    outcome.add_column("winner")
    outcome.add_column("reason")
    outcome.add_row("original", str(real[0] or "not recorded"), str(real[1] or "not recorded"))
    replayed: tuple[str | None, str | None]
    if result.outcome is None:
        replayed = ("undecided", "end of the data")
    elif result.played_out_s > 0:
        replayed = (simulated[0], f"{simulated[1]} ({result.played_out_s:.1f} s after the data)")
    else:
        replayed = simulated
    outcome.add_row("replay", *map(str, replayed))
    console.print(outcome)
    for prefix, notes in (
        ("warning: implausible data replayed anyway: ", result.warnings),
        ("data contradicts itself: ", result.contradictions),
        ("inferred: ", result.inferred),
    ):
        for note in notes:  # they name players: a line as long as a screen's, whole in the files
            text = shortened(visible(prefix + note), NOTE_LIMIT)
            console.print(text, style="yellow", markup=False, highlight=False)
    if options.combat:
        console.print(f"deaths decided by: {options.deaths}")
        used = result.utility
        console.print(
            "utility the fight heeds: "
            + (", ".join(f"{n} {k}" for k, n in used.items()) if used else "none in the data")
        )
        for line in map_warnings(choice, [round_.map_name]):
            console.print(f"warning: {line}", style="yellow", markup=False)
    _show_bomb(console, result.bomb_row())
    for title, names in (
        ("clock protocol", METRIC_NAMES_CLOCK),
        ("paper protocol", METRIC_NAMES_PAPER),
    ):
        table = Table(title=f"{title} (metres)")
        table.add_column("player")
        table.add_column("side")
        for name in names:
            table.add_column(name, justify="right")
        for _, row in players.iterrows():
            table.add_row(
                shortened(str(row["player"])),  # whole in players.csv
                row["side"],
                *("–" if not np.isfinite(row[name]) else f"{row[name]:.3f}" for name in names),
            )
        console.print(table)
    timing = Table(title="timing and fate")
    for column in ("player", "late share", "late p95 (s)", "stuck", "recoveries", "died", "death"):
        timing.add_column(column, justify="right" if column != "player" else "left")
    for _, row in players.iterrows():
        timing.add_row(
            shortened(str(row["player"])),
            f"{row['late_share']:.1%}" if np.isfinite(row["late_share"]) else "–",
            f"{row['late_p95_s']:.2f}" if np.isfinite(row["late_p95_s"]) else "–",
            str(row["stuck"]),
            str(row["recoveries"]),
            f"{'yes' if row['died_original'] else 'no'} / {'yes' if row['died_replay'] else 'no'}",
            row["death"] or "–",
        )
    console.print(timing)
    console.print(f"replay written to {run.folder}")


def _show_bomb(console: Console, bomb: BombRow | None) -> None:
    """The bomb of the data against the replay's: plant, defuse and the data's anomalies."""
    if bomb is None or not bomb["bomb_recorded"]:
        console.print("bomb: off" if bomb is None else "bomb: not recorded in the data")
        return
    table = Table(title="the bomb")
    for column in ("", "data", "replay", "error"):
        table.add_column(column, justify="left" if not column else "right")
    plant_error = "–"
    if np.isfinite(bomb["plant_time_error_s"]):
        plant_error = f"{bomb['plant_time_error_s']:+.2f} s"
        if np.isfinite(bomb["plant_position_error_m"]):
            plant_error += f", {bomb['plant_position_error_m']:.2f} m"
    table.add_row(
        "plant",
        _yes(bomb["plant_data"], bomb["plant_site_data"]),
        _yes(bomb["plant_replay"], bomb["plant_site_replay"]),
        plant_error,
    )
    defuse_error = bomb["defuse_time_error_s"]
    table.add_row(
        "defuse",
        _yes(bomb["defuse_data"], ""),
        _yes(bomb["defuse_replay"], ""),
        f"{defuse_error:+.2f} s" if np.isfinite(defuse_error) else "–",
    )
    console.print(table)
    if bomb["bomb_anomalies"]:
        console.print(f"bomb data anomalies: {bomb['bomb_anomalies']}", style="yellow")


def _yes(happened: bool, site: str) -> str:
    return f"yes ({site})" if happened and site else "yes" if happened else "no"
