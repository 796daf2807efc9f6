"""The consoles the commands print with.

Markup is off: text from the data or the user (player names, match ids, file names, error
messages) is printed as it is, never read as rich markup (a player named "[/x]" would otherwise
stop the command); colour is given as a `style`. And every string printed, in a line or a
table's cell, has its control characters made visible (`decoy_cli.text.visible`, keeping only
newlines): a name holding ESC[2J cannot clear or repaint the user's terminal.
"""

from __future__ import annotations

from collections.abc import Iterable
from typing import Any

from rich.console import Console
from rich.segment import Segment
from rich.text import Text

from decoy_cli.text import visible


class _Console(Console):
    """A rich console whose text is rendered with its control characters visible: strings
    before layout (so a table's columns fit them), and every segment of text after, whatever
    made it (a `Text`, a progress bar's description)."""

    def render_str(self, text: str, **options: Any) -> Text:
        return super().render_str(visible(text, keep="\n"), **options)

    def render(self, renderable: Any, options: Any = None) -> Iterable[Segment]:
        for segment in super().render(renderable, options):
            if segment.control is None and segment.text:
                shown = visible(segment.text, keep="\n")
                if shown is not segment.text:
                    segment = Segment(shown, segment.style)
            yield segment


def make_console(*, stderr: bool = False) -> Console:
    """A console on stdout (or stderr) that prints text literally (module doc)."""
    return _Console(stderr=stderr, markup=False)
