"""The consoles the commands print with.

Markup is off: text from the data or the user (player names, match ids, file names, error
messages) is printed as it is, never read as rich markup (a player named "[/x]" would otherwise
stop the command); colour is given as a `style`.
"""

from __future__ import annotations

from rich.console import Console


def make_console(*, stderr: bool = False) -> Console:
    """A console on stdout (or stderr) that prints text literally (module doc)."""
    return Console(stderr=stderr, markup=False)
