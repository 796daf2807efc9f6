"""Markdown pieces shared by the evaluation's report sections: numbers, tables, long lists.
Text from data goes in through `decoy_cli.text.md_inline` or `md_code` (re-exported here)."""

from __future__ import annotations

import math
import re
from typing import SupportsFloat

from decoy_cli.text import md_code, md_inline, visible

__all__ = ["first_rows", "interval", "md_code", "md_inline", "md_table", "num", "p_value"]

REPORT_ROWS_SHOWN = 20
"""Rows of a failure, warning or anomaly list shown in the report; the CSVs hold them all."""


def num(value: SupportsFloat | None, digits: int = 3) -> str:
    """A number with fixed digits; "–" for NaN or None."""
    if value is None:
        return "–"
    value = float(value)
    return "–" if math.isnan(value) else f"{value:.{digits}f}"


def md_table(header: list[str], rows: list[list[str]]) -> str:
    """A Markdown table; no cell can end its row or add a column (control characters visible,
    "|" escaped). Cells holding text from data are `md_inline` or `md_code` already."""
    lines = ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
    lines += ["| " + " | ".join(_cell(cell) for cell in row) + " |" for row in rows]
    return "\n".join(lines)


def _cell(text: str) -> str:
    return re.sub(r"(?<!\\)\|", r"\\|", visible(text))


def first_rows(header: list[str], rows: list[list[str]], csv_name: str) -> str:
    """A table of the first `REPORT_ROWS_SHOWN` rows, and where the others are."""
    text = md_table(header, rows[:REPORT_ROWS_SHOWN])
    if len(rows) > REPORT_ROWS_SHOWN:
        text += f"\n\n… and {len(rows) - REPORT_ROWS_SHOWN} more in `{csv_name}`."
    return text


def interval(low: float, high: float) -> str:
    """A 95% interval as "[low, high]"; "" when there is none (too few rounds)."""
    return "" if math.isnan(low) else f"[{num(low)}, {num(high)}]"


def p_value(p: float) -> str:
    """A p-value in two significant digits; "–" when there is none."""
    return "–" if math.isnan(p) else f"{p:.2g}"
