"""The `decoy` command-line application: registers the subcommands, nothing else."""

from __future__ import annotations

import sys

import typer
from typer.core import TyperGroup

from decoy_cli import __version__
from decoy_cli.commands import (
    bench,
    build_waypoints,
    download,
    evaluate,
    info,
    make_sample,
    models,
    replay,
    snap,
    train,
)
from decoy_cli.commands.help_text import reflow_help
from decoy_cli.errors import DecoyError

_debug = False


class _Group(TyperGroup):
    """Turns a `DecoyError` into one line on stderr and exit code 1 (a traceback with --debug)."""

    def invoke(self, ctx: typer.Context):  # type: ignore[override]
        try:
            return super().invoke(ctx)
        except DecoyError as error:
            if _debug:
                raise
            typer.echo(f"error: {error}", err=True)
            sys.exit(1)


app = typer.Typer(
    cls=_Group,
    help="Replay real CS:GO rounds on a de_dust2 waypoint graph and measure replay fidelity.",
    no_args_is_help=True,
    add_completion=False,
    pretty_exceptions_enable=False,
)


def _show_version(value: bool) -> None:
    if value:
        typer.echo(f"decoy {__version__}")
        raise typer.Exit()


@app.callback()
def main(
    version: bool = typer.Option(
        False, "--version", callback=_show_version, is_eager=True, help="Print the version."
    ),
    debug: bool = typer.Option(False, "--debug", help="Show a traceback for errors."),
) -> None:
    """Replay real CS:GO rounds on a de_dust2 waypoint graph and measure replay fidelity."""
    global _debug
    _debug = debug


app.command("bench")(bench.bench)
app.command("build-waypoints")(build_waypoints.build_waypoints)
app.command("download")(download.download)
app.command("evaluate")(evaluate.evaluate)
app.command("info")(info.info)
app.command("make-sample")(make_sample.make_sample)
app.command("replay")(replay.replay)
app.command("snap")(snap.snap)
app.add_typer(models.app, name="models")
app.add_typer(train.app, name="train")
reflow_help(app)  # last: help reflows to the terminal's width instead of keeping docstring wraps
