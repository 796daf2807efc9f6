"""Help text that reflows to the terminal: docstrings and `help=` strings lose their hard wraps.

Typer (rich mode) keeps every line break of a command's docstring after its first paragraph, so
a docstring wrapped at 100 columns broke mid-sentence at 80 and stopped short at 120.
`reflow_help(app)` rewrites, once at registration, the help of every command, sub-app and
option of a Typer app: the lines of a paragraph are joined into one, so rich wraps it to the
terminal's width; blank lines still separate paragraphs, and a line that starts a list item
(`* `, `- `, `1. `) still starts its own line. A paragraph starting with click's `\\b` and
anything after `\\f` are left as written.
"""

from __future__ import annotations

import inspect
import re

import typer
from typer.models import DefaultPlaceholder, ParameterInfo

_ITEM = re.compile(r"([*\-•]|\d+[.)])\s")
_PARAGRAPHS = re.compile(r"\n[ \t]*\n")


def reflow(text: str) -> str:
    """`text` with the line breaks inside each paragraph and list item removed."""
    head, feed, tail = text.partition("\f")
    paragraphs = []
    for paragraph in _PARAGRAPHS.split(inspect.cleandoc(head).strip()):
        if paragraph.startswith("\b"):
            paragraphs.append(paragraph)
            continue
        lines: list[str] = []
        for line in paragraph.splitlines():
            line = line.strip()
            if lines and line and not _ITEM.match(line):
                lines[-1] = f"{lines[-1]} {line}"
            elif line:
                lines.append(line)
        paragraphs.append("\n".join(lines))
    return "\n\n".join(paragraphs) + feed + tail


def _reflow_parameters(callback) -> None:
    for parameter in inspect.signature(callback).parameters.values():
        info = parameter.default
        if isinstance(info, ParameterInfo) and isinstance(info.help, str):
            info.help = reflow(info.help)


def reflow_help(app: typer.Typer) -> None:
    """Reflow the help of every command, sub-app and option registered on `app` (recursively)."""
    if isinstance(app.info.help, str):
        app.info.help = reflow(app.info.help)
    callback = app.registered_callback
    if callback is not None:
        if isinstance(callback.help, str) and not isinstance(callback.help, DefaultPlaceholder):
            callback.help = reflow(callback.help)
        if callback.callback is not None:
            _reflow_parameters(callback.callback)
    for command in app.registered_commands:
        text = command.help if isinstance(command.help, str) else inspect.getdoc(command.callback)
        if text:
            command.help = reflow(text)
        if command.callback is not None:
            _reflow_parameters(command.callback)
    for group in app.registered_groups:
        if isinstance(group.help, str) and not isinstance(group.help, DefaultPlaceholder):
            group.help = reflow(group.help)
        if group.typer_instance is not None:
            reflow_help(group.typer_instance)
