"""Every command's `--help` reads cleanly at 80 and 120 columns: no line is wider than the
terminal, paragraphs reflow to its width instead of keeping the docstrings' hard wraps (a line
never ends where the next line's first word would still have fitted), and every option is named.
"""

from __future__ import annotations

import re
from itertools import pairwise

import pytest
import typer
from typer.testing import CliRunner

from decoy_cli.cli import app
from decoy_cli.commands.help_text import reflow

WIDTHS = (80, 120)
# Lines that start something of their own: list items, and the notes Typer adds to an option.
_OWN_LINE = re.compile(r"([*\-•]|\d+[.)])\s|\[(default|env var|required)")
_CELL_GAP = re.compile(r"\S(?:  +)(?=\S)")


def _commands(command, path: tuple[str, ...] = ()):
    yield path, command
    if hasattr(command, "commands"):  # a group (Typer may use its own copy of click)
        for name, sub in command.commands.items():
            yield from _commands(sub, (*path, name))


COMMANDS = list(_commands(typer.main.get_command(app)))


def _early_breaks(lines: list[str], width: int) -> list[str]:
    """Pairs of lines in one paragraph where the first ended although the second line's first
    word would have fitted after it within `width` characters."""
    found = []
    for first, second in pairwise(lines):
        if not first.strip() or not second.strip() or _OWN_LINE.match(second.lstrip()):
            continue
        word = second.split()[0]
        if len(first.rstrip()) + 1 + len(word) <= width:
            found.append(f"{first.rstrip()!r} / {second.strip()!r}")
    return found


def _panels(lines: list[str]) -> list[list[str]]:
    """The inside of each boxed panel (Arguments, Options, Commands), borders removed."""
    panels, current = [], None
    for line in lines:
        if line.startswith("╭"):
            current = []
        elif line.startswith("╰"):
            panels.append(current)
            current = None
        elif current is not None and line.startswith("│"):
            current.append(line.rstrip()[1:-1])
    return panels


def _help_column(panel: list[str]) -> int:
    """Where the panel's last column (the help) starts: the commonest start of a line's last
    cell, as most lines are continuations of a help text."""
    starts: dict[int, int] = {}
    for line in panel:
        if not line.strip():
            continue
        gaps = list(_CELL_GAP.finditer(line))
        start = gaps[-1].end() if gaps else len(line) - len(line.lstrip())
        starts[start] = starts.get(start, 0) + 1
    return max(starts, key=lambda s: (starts[s], s))


def _panel_early_breaks(panel: list[str]) -> list[str]:
    column = _help_column(panel)
    cell_width = len(panel[0]) - column - 1  # the cell's right padding
    found, cells = [], []
    for line in panel:
        if line[:column].strip():  # a new row: its help cell is a new paragraph
            found += _early_breaks(cells, cell_width)
            cells = []
        cells.append(line[column:])
    return found + _early_breaks(cells, cell_width)


@pytest.mark.parametrize("width", WIDTHS)
@pytest.mark.parametrize(
    ("path", "command"), COMMANDS, ids=[" ".join(p) or "decoy" for p, _ in COMMANDS]
)
def test_help_reflows_to_the_terminal(path: tuple[str, ...], command, width: int) -> None:
    result = CliRunner().invoke(
        app, [*path, "--help"], env={"COLUMNS": str(width)}, terminal_width=width
    )
    assert result.exit_code == 0, result.output
    lines = result.output.splitlines()
    too_wide = [line for line in lines if len(line) > width]
    assert not too_wide, f"wider than {width}:\n" + "\n".join(too_wide)

    # The description: the lines between the usage line and the first panel.
    top = lines[: next((i for i, line in enumerate(lines) if line.startswith("╭")), len(lines))]
    description = [line for line in top if not line.strip().startswith("Usage:")]
    breaks = _early_breaks(description, width - 1)  # one space of padding on the right
    for panel in _panels(lines):
        breaks += _panel_early_breaks(panel)
    assert not breaks, "hard-wrapped lines:\n" + "\n".join(breaks) + "\n\n" + result.output

    for param in command.params:
        if param.param_type_name == "option":
            for name in (*param.opts, *param.secondary_opts):
                assert name in result.output, f"{name} missing from:\n{result.output}"


def test_reflow_joins_paragraph_lines_and_keeps_paragraphs_and_items() -> None:
    text = """First line
    goes on.

    A paragraph
    wrapped by hand.

    * an item
      continued
    * another
    1. numbered
    \f
    kept
    as is"""
    assert reflow(text) == (
        "First line goes on.\n\nA paragraph wrapped by hand.\n\n"
        "* an item continued\n* another\n1. numbered\f\n    kept\n    as is"
    )
    assert reflow("\b\nkeep\nthese lines") == "\b\nkeep\nthese lines"


def test_the_cli_needs_no_click() -> None:
    """`pip install -e .` does not install click (Typer ships its own): the CLI must start and
    report errors without it (the README's first command)."""
    import subprocess
    import sys

    code = (
        "import sys; sys.modules['click'] = None\n"
        "from typer.testing import CliRunner\n"
        "from decoy_cli.cli import app\n"
        "result = CliRunner().invoke(app, ['info', '/no/such/file.json'])\n"
        "print(result.exit_code, result.stderr.strip())\n"
    )
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert done.returncode == 0, done.stderr
    assert done.stdout.strip() == "1 error: /no/such/file.json: no such file or folder"
