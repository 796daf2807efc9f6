"""`decoy info PATH[:ROUND]`: what a match (an ESTA file, awpy's tables), one of its rounds, or a
folder holds, and what it does not record."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import typer
from rich.console import Console
from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn
from rich.table import Table
from rich.text import Text

from decoy_cli.commands._console import make_console
from decoy_cli.commands._options import RATE_HELP
from decoy_cli.errors import EstaError
from decoy_cli.esta import Match, Round, iter_match_files, parse_round_address, read_match
from decoy_cli.esta.awpy.tables import is_awpy_source
from decoy_cli.replay.missing import lacking
from decoy_cli.text import shortened


def info(
    target: str = typer.Argument(
        ...,
        metavar="PATH[:ROUND]",
        help="A match (an ESTA .json.xz or .json, an awpy 2 .zip, a folder of awpy 3 tables, "
        "a .dem with awpy 3 installed), PATH:ROUND for one round, or a folder of matches.",
    ),
    rate: float | None = typer.Option(None, "--rate", help=RATE_HELP, min=0.1, max=128),
) -> None:
    """Show the rounds of a match, the players of one round, or the matches in a folder."""
    console = make_console()
    path = Path(target)
    if path.is_file() or is_awpy_source(path):
        _show_match(console, read_match(path, rate=rate))
    elif path.is_dir():
        _show_folder(console, path, rate)
    else:
        try:
            file, num = parse_round_address(target)
        except EstaError:
            raise EstaError(f"{target}: no such file or folder") from None
        _show_round(console, read_match(file, rate=rate).round(num))


def _show_folder(console: Console, folder: Path, rate: float | None) -> None:
    """One row per match file: map, rounds read and failed; unreadable files and failed rounds
    fail the command, as they do for one file."""
    files = iter_match_files(folder)
    table = Table(title=f"{folder}: {len(files)} match files")
    for column in ("file", "map", "rounds", "failed rounds"):
        table.add_column(column, justify="right" if "rounds" in column else "left", overflow="fold")
    unreadable: list[str] = []
    failed_rounds = 0
    progress = Progress(
        TextColumn("reading"),
        BarColumn(),
        MofNCompleteColumn(),
        console=make_console(stderr=True),
        transient=True,
    )
    with progress:
        for file in progress.track(files):
            try:
                match = read_match(file, rate=rate)
            except EstaError as error:
                unreadable.append(str(error))
                table.add_row(file.name, Text("unreadable", style="red"), "", "")
                continue
            failed_rounds += len(match.round_errors)
            table.add_row(
                file.name,
                match.map_name,
                str(len(match.rounds)),
                str(len(match.round_errors)),
            )
    console.print(table)
    for message in unreadable:
        console.print(message, style="red", highlight=False)
    if unreadable or failed_rounds:
        raise EstaError(
            f"{folder}: {len(unreadable)} of {len(files)} match files are unreadable, "
            f"{failed_rounds} rounds failed (`decoy info FILE` says why)"
        )


def _show_match(console: Console, match: Match) -> None:
    """One row per round; rounds that failed are listed after the table and fail the command."""
    table = Table(
        title=f"{match.match_id}: {match.map_name or 'unknown map'}, {match.tick_rate} tick, "
        f"{len(match.round_numbers)} rounds ({match.meta.get('source', 'ESTA')})"
    )
    for column in ("round", "frames", "T", "CT", "plant tick", "winner", "reason", "lacks"):
        table.add_column(column, justify="left" if column in ("reason", "lacks") else "right")
    for played in match.rounds:
        seen = np.any(played.present, axis=1)
        table.add_row(
            str(played.round_num),
            str(played.num_frames),
            str(int(seen[played.side_indices("T")].sum())),
            str(int(seen[played.side_indices("CT")].sum())),
            _or_dash(played.bomb_plant_tick),
            _or_dash(played.winning_side),
            _or_dash(played.end_reason),
            ", ".join(lacking(played)) or "-",
        )
    console.print(table)
    _show_recorded(console, match)
    if any(lacking(played) for played in match.rounds):
        console.print(
            "lacks: fields the game needs that the file does not record; a replay fills them "
            "by rule and names them (--missing-fields)",
            highlight=False,
        )
    for error in match.round_errors.values():
        console.print(str(error), style="red", highlight=False)
    if match.round_errors:
        failed = len(match.round_errors)
        raise EstaError(
            f"{match.path}: {failed} of {len(match.round_numbers)} rounds are unreadable"
        )


def _show_recorded(console: Console, match: Match) -> None:
    """For awpy's tables: the tick rate's source and what the ticks do not record."""
    rule = match.meta.get("tick_rate_rule")
    if rule:
        console.print(f"tick rate {match.tick_rate}: {rule}", highlight=False)
    missing = sorted({name for played in match.rounds for name in played.not_recorded})
    if match.meta.get("source") in (None, "ESTA"):
        return
    console.print(
        "not recorded: " + (", ".join(missing) or "nothing the replay uses"), highlight=False
    )
    warned = [(r.round_num, w) for r in match.rounds for w in r.warnings]
    for num, warning in warned:
        console.print(f"round {num}: {warning}", style="yellow", highlight=False)


def _show_round(console: Console, played: Round) -> None:
    """The round's facts and one row per player with frame counts."""
    seconds = played.frame_seconds
    span = f"{seconds[0]:.1f}-{seconds[-1]:.1f} s" if played.num_frames else "no frames"
    console.print(
        f"{played.match_id} round {played.round_num} ({played.map_name or 'unknown map'}): "
        f"{played.num_frames} frames, {span}, ticks {_or_dash(played.start_tick)}-"
        f"{_or_dash(played.end_tick)}, winner {_or_dash(played.winning_side)} "
        f"({_or_dash(played.end_reason)}), plant tick {_or_dash(played.bomb_plant_tick)}; "
        f"{len(played.damages)} damages, {len(played.kills)} kills, "
        f"{len(played.bomb_events)} bomb events; read from {played.source}"
        + (f"; not recorded: {', '.join(played.not_recorded)}" if played.not_recorded else ""),
        highlight=False,
    )
    if not played.players:
        console.print("no player appears in any frame")
        return
    table = Table()
    for column in ("player", "name", "side", "frames present", "frames alive", "last hp"):
        table.add_column(
            column, justify="right" if "frames" in column or "hp" in column else "left"
        )
    for row, player in enumerate(played.players):
        known = np.flatnonzero(played.present[row])
        last_hp = str(int(played.hp[row, known[-1]])) if known.size else "-"
        table.add_row(
            shortened(player.key),
            shortened(player.name),
            player.side,
            str(int(played.present[row].sum())),
            str(int(played.alive[row].sum())),
            last_hp,
        )
    console.print(table)


def _or_dash(value: object) -> str:
    """The value as text, "-" for None."""
    return "-" if value is None else str(value)
