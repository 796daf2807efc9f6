"""Text from data made harmless where it is shown: on a terminal, in Markdown, in a CSV cell.

A match file is anyone's file: a player name, a team name, a match id or a file name can hold
terminal control sequences (ESC[2J clears the screen), Unicode direction overrides that reorder
what is shown, Markdown that turns a report's table into a link, or a spreadsheet formula
(`=HYPERLINK(...)`) that Excel and LibreOffice evaluate when the CSV is opened. These helpers
are applied where text leaves the program (the consoles, the error line, the Markdown tables
and report, the CSV writer), not where it is read, so the data itself stays as recorded:

* `visible`: control characters (C0, DEL, C1), line and paragraph separators and the
  direction controls written as Python escapes (`\\x1b`, `\\u202e`), so they show and act not;
* `md_inline` and `md_code`: a string for Markdown text or a code span;
* `csv_inert`: a table whose text cells cannot start a formula (a leading `'`, the common
  convention, before `=`, `+`, `-`, `@`, tab or carriage return) and hold no control
  character; numbers, and text that reads as a number, are left as they are;
* `shortened`: a text cut to a length with a marker (`CUT_MARK`), so that a name of any length
  takes a bounded place where it is shown (`shown_name`: `NAME_LIMIT` characters in figures,
  terminal tables and the page); CSV files keep it in full.
"""

from __future__ import annotations

import re

import pandas as pd

_BIDI = "\u061c\u200e\u200f\u202a-\u202e\u2066-\u2069"
_CONTROLS = re.compile(f"[\x00-\x1f\x7f-\x9f\u2028\u2029{_BIDI}]")
_MARKDOWN = re.compile(r"([\\`*_\[\]<>|~&])")
_NUMBER = re.compile(r"[+-]?(\d+\.?\d*|\.\d+)([eE][+-]?\d+)?")
FORMULA_STARTS = ("=", "+", "-", "@", "\t", "\r")
"""What a spreadsheet reads as the start of a formula (OWASP's CSV injection list)."""
CUT_MARK = "…"
"""Ends a text `shortened` cut."""
NAME_LIMIT = 48
"""Characters of a name (a player's) shown where it is drawn: half again Steam's 32-character
names, so a real name is shown whole, even with a control character or two written as
escapes."""


def visible(text: str, keep: str = "") -> str:
    """`text` with every control character (module doc) written as its Python escape, except
    the characters in `keep` (a console keeps "\\n" of its own lines)."""
    if not _CONTROLS.search(text):
        return text
    return _CONTROLS.sub(lambda m: m[0] if m[0] in keep else _escape(m[0]), text)


def shortened(text: str, limit: int = NAME_LIMIT) -> str:
    """`text` when it has at most `limit` characters, else its first `limit` - 1 and
    `CUT_MARK` (`limit` characters in all)."""
    return text if len(text) <= limit else text[: max(limit - 1, 0)] + CUT_MARK


def shown_name(name: str) -> str:
    """A name from the data as it is shown where it is drawn: `visible`, then `shortened` to
    `NAME_LIMIT` characters."""
    return shortened(visible(name))


def _escape(char: str) -> str:
    code = ord(char)
    return f"\\x{code:02x}" if code < 0x100 else f"\\u{code:04x}"


def md_inline(text: str) -> str:
    """`text` for Markdown prose or a table cell: visible, and Markdown's punctuation escaped,
    so a name cannot make a link, an image, a tag or a new table column."""
    return _MARKDOWN.sub(r"\\\1", visible(text))


def md_code(text: str) -> str:
    """`text` as a Markdown code span: visible, fenced by more backticks than it holds in a
    row (CommonMark), so no backtick in it ends the span early."""
    text = visible(text)
    longest = max((len(run) for run in re.findall("`+", text)), default=0)
    fence = "`" * (longest + 1)
    pad = " " if text.startswith("`") or text.endswith("`") else ""
    return f"{fence}{pad}{text}{pad}{fence}"


def csv_cell(value: object) -> object:
    """One CSV cell made inert (module doc); anything but text is returned as it is."""
    if not isinstance(value, str):
        return value
    if value.startswith(FORMULA_STARTS) and not _NUMBER.fullmatch(value):
        value = "'" + value
    return visible(value)


def csv_inert(frame: pd.DataFrame) -> pd.DataFrame:
    """`frame` with its text cells and column names made inert (`csv_cell`); number columns
    are untouched, and a frame with no text is returned as it is."""
    names = [csv_cell(c) for c in frame.columns]
    texts = [i for i, dtype in enumerate(frame.dtypes) if _textual(dtype)]
    if not texts and names == list(frame.columns):
        return frame
    frame = frame.copy()
    for i in texts:
        frame.isetitem(i, frame.iloc[:, i].map(csv_cell))
    frame.columns = pd.Index(names)
    return frame


def _textual(dtype: object) -> bool:
    return pd.api.types.is_object_dtype(dtype) or isinstance(
        dtype, pd.StringDtype | pd.CategoricalDtype
    )
