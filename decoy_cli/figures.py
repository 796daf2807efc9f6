"""Pieces every figure shares: the map drawn from the nav areas, and saving a PNG atomically.

Text in a figure may come from the data (a legend of player names, a title with a match id):
`save_figure` bounds every text the figure holds before it is laid out, so that no figure grows
with a name (a 100,000-character name in a legend made a figure a million pixels wide, saved
to fit it): a legend entry is cut to `LEGEND_LIMIT` characters and any other text to
`TEXT_LIMIT` a line and `TEXT_LINES` lines, with a marker (`decoy_cli.text.shortened`); control
characters are written as escapes and no text is read as mathtext (a `$` in a name is a `$`).

matplotlib is imported inside the functions (headless Agg backend), so commands that draw
nothing do not pay for it.
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Protocol

import numpy as np

from decoy_cli.csgo import HAMMER_TO_M
from decoy_cli.files import write_atomic
from decoy_cli.text import CUT_MARK, NAME_LIMIT, shortened, visible

if TYPE_CHECKING:
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure

LEGEND_LIMIT = NAME_LIMIT + 16
"""Characters of a legend entry: a name and a few words about it ("NAME (CT): original")."""
TEXT_LIMIT = 120
"""Characters of a line of any other text of a figure (titles, labels, notes)."""
TEXT_LINES = 4
"""Lines of any text of a figure."""


class NavAreas(Protocol):
    """A map's nav areas as rectangles, Hammer units (`decoy_cli.world.navmesh.NavMesh`)."""

    @property
    def x_min(self) -> np.ndarray: ...
    @property
    def y_min(self) -> np.ndarray: ...
    @property
    def x_max(self) -> np.ndarray: ...
    @property
    def y_max(self) -> np.ndarray: ...


def draw_nav_areas(ax: Axes, nav: NavAreas, **style: object) -> None:
    """Draw the walkable map (the nav areas as grey rectangles, metres) under a plot."""
    from matplotlib.collections import PolyCollection

    corners = np.stack(
        [
            np.column_stack([nav.x_min, nav.y_min]),
            np.column_stack([nav.x_max, nav.y_min]),
            np.column_stack([nav.x_max, nav.y_max]),
            np.column_stack([nav.x_min, nav.y_max]),
        ],
        axis=1,
    )
    look: dict[str, object] = {
        "facecolor": "#e6e6e6",
        "edgecolor": "#cfcfcf",
        "lw": 0.3,
        "zorder": 0,
    }
    look.update(style)
    # The stubs want a Sequence of polygons; a (N, 4, 2) array is one (and takes the fast path).
    ax.add_collection(PolyCollection(corners * HAMMER_TO_M, **look))  # type: ignore[arg-type]


def bound_texts(fig: Figure) -> None:
    """Cut every text of the figure to its bounds (module doc), in place."""
    from matplotlib.legend import Legend
    from matplotlib.text import Text

    entries = {id(t) for legend in fig.findobj(Legend) for t in legend.get_texts()}
    for text in fig.findobj(Text):
        assert isinstance(text, Text)
        shown = text.get_text()
        limit = LEGEND_LIMIT if id(text) in entries else TEXT_LIMIT
        bounded = _bounded(shown, limit)
        if bounded != shown:
            text.set_text(bounded)
        text.set_parse_math(False)


def _bounded(text: str, limit: int) -> str:
    """`text` with control characters (but newlines) as escapes, each line cut to `limit`
    characters and at most `TEXT_LINES` lines."""
    lines = visible(text, keep="\n").split("\n")
    shown = [shortened(line, limit) for line in lines[:TEXT_LINES]]
    if len(lines) > TEXT_LINES and not shown[-1].endswith(CUT_MARK):
        shown[-1] += CUT_MARK
    return "\n".join(shown)


def save_figure(fig: Figure, path: str | Path, dpi: int = 130) -> None:
    """Save a matplotlib figure as PNG (atomically), its texts bounded (module doc), and close
    it."""
    import matplotlib.pyplot as plt

    try:
        bound_texts(fig)
        write_atomic(path, lambda tmp: fig.savefig(tmp, format="png", dpi=dpi, bbox_inches="tight"))
    finally:
        plt.close(fig)
