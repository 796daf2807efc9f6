"""The `decoy` command-line application: registers the subcommands, nothing else."""

from __future__ import annotations

import sys

import typer
from typer.core import TyperGroup
from typer.exceptions import TyperException

from decoy_cli import __version__
from decoy_cli.commands import (
    bench,
    build_waypoints,
    compare,
    download,
    evaluate,
    info,
    make_sample,
    models,
    replay,
    snap,
    train,
    view,
)
from decoy_cli.commands.help_text import reflow_help
from decoy_cli.errors import DecoyError, describe_bug
from decoy_cli.text import visible

_debug = False


class _Group(TyperGroup):
    """The one error boundary of every command: a `DecoyError` (bad input) or an `OSError` (a
    path the system refuses, a full disk) is one `error:` line on stderr and exit code 1; any
    other exception is a bug, reported in one line as such with exit code 2. `--debug` shows
    the traceback instead. A usage error (an unknown option, a value not among an option's
    choices) is one `error:` line too, with exit code 2 as Click gives it; Typer's own exits
    pass through."""

    def invoke(self, ctx: typer.Context):  # type: ignore[override]
        try:
            return super().invoke(ctx)
        except (typer.Exit, typer.Abort):
            raise  # Typer's own exits and aborts
        except TyperException as error:
            if getattr(error, "exit_code", None) != 2:  # not a usage error (Typer's own class)
                raise
            context = getattr(error, "ctx", None)
            command = f"{context.command_path} --help" if context is not None else "--help"
            _fail(f"{error.format_message()} (see {command})", 2)
        except DecoyError as error:
            _fail(str(error), 1)
        except BrokenPipeError:
            _reader_gone()
        except OSError as error:
            _fail(_os_problem(error), 1)
        except Exception as error:
            _fail(_bug(error), 2)


def _fail(message: str, code: int) -> None:
    if _debug:
        raise
    typer.echo(f"error: {visible(message)}", err=True)  # one line, no control character
    sys.exit(code)


def _reader_gone() -> None:
    """The program reading the output went away (`decoy info x | head`): stop quietly, as a
    Unix tool does, with nothing more written to the closed pipe."""
    import contextlib
    import os

    with contextlib.suppress(OSError, ValueError):  # stdout is not a file (captured in a test)
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
    sys.exit(1)


def _os_problem(error: OSError) -> str:
    """An OSError as one line naming the path, e.g. "x/y.json: File name too long"."""
    reason = error.strerror or str(error)
    return f"{error.filename}: {reason}" if error.filename else reason


def _bug(error: Exception) -> str:
    summary, where = describe_bug(error)
    at = f" at {where}" if where else ""
    return (
        f"internal error (a bug in decoy, please report it): {summary}{at}; rerun with --debug "
        "for the traceback"
    )


app = typer.Typer(
    cls=_Group,
    help="Replay real CS:GO rounds on waypoint graphs of eight maps and measure replay fidelity.",
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
    """Replay real CS:GO rounds on waypoint graphs of eight maps and measure replay fidelity."""
    global _debug
    _debug = debug


app.command("bench")(bench.bench)
app.command("build-waypoints")(build_waypoints.build_waypoints)
app.command("compare")(compare.compare)
app.command("download")(download.download)
app.command("evaluate")(evaluate.evaluate)
app.command("info")(info.info)
app.command("make-sample")(make_sample.make_sample)
app.command("replay")(replay.replay)
app.command("snap")(snap.snap)
app.command("view")(view.view)
app.add_typer(models.app, name="models")
app.add_typer(train.app, name="train")
reflow_help(app)  # last: help reflows to the terminal's width instead of keeping docstring wraps
