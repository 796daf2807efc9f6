"""`decoy view FOLDER`: one self-contained HTML page of an evaluate run or of a replay."""

from __future__ import annotations

from pathlib import Path

import typer

from decoy_cli.commands._console import make_console
from decoy_cli.errors import DecoyError
from decoy_cli.evaluate.view_page import run_page
from decoy_cli.view.page import round_index, write_page
from decoy_cli.view.replay_folder import is_replay_folder, replay_page

PAGE = "view.html"


def view(
    folder: Path = typer.Argument(
        ..., help="Output folder of `decoy evaluate` or of `decoy replay`.", metavar="FOLDER"
    ),
    round_label: str | None = typer.Option(
        None, "--round", metavar="MATCH:ROUND", help="The round the page opens on."
    ),
    out: Path | None = typer.Option(
        None, "--out", help="Where to write the page. Default: view.html in FOLDER."
    ),
) -> None:
    """Write one HTML page to look at the rounds, real against replay: the run's tables, its
    player-rounds sortable by any metric (a row opens its round at its largest error), and a
    round player over the map with time slider, play and pause, deaths, kills and the bomb.
    Its data and script are inside it: it opens offline, from anywhere."""
    if not folder.is_dir():
        raise DecoyError(f"{folder}: no such folder (give an output folder of decoy evaluate)")
    data = replay_page(folder) if is_replay_folder(folder) else run_page(folder)
    if round_label is not None:
        data["initial"] = round_index(data, round_label)
    target = write_page(out or folder / PAGE, data)
    size = target.stat().st_size
    rounds = len(data["rounds"])
    make_console().print(
        f"{rounds} round{'' if rounds == 1 else 's'}, {len(data['players']['rows'])} "
        "player-rounds: "
        f"{target} ({size / 1e6:.1f} MB)",
        highlight=False,
        soft_wrap=True,
    )
