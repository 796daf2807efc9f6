"""Pieces every figure shares: the map drawn from the nav areas, and saving a PNG atomically.

matplotlib is imported inside the functions (headless Agg backend), so commands that draw
nothing do not pay for it.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from decoy_cli.csgo import HAMMER_TO_M
from decoy_cli.files import write_atomic


def draw_nav_areas(ax: Any, nav: Any, **style: Any) -> None:
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
    look: dict[str, Any] = {"facecolor": "#e6e6e6", "edgecolor": "#cfcfcf", "lw": 0.3, "zorder": 0}
    look.update(style)
    # The stubs want a Sequence of polygons; a (N, 4, 2) array is one (and takes the fast path).
    ax.add_collection(PolyCollection(corners * HAMMER_TO_M, **look))  # type: ignore[arg-type]


def save_figure(fig: Any, path: str | Path, dpi: int = 130) -> None:
    """Save a matplotlib figure as PNG (atomically) and close it."""
    import matplotlib.pyplot as plt

    try:
        write_atomic(path, lambda tmp: fig.savefig(tmp, format="png", dpi=dpi, bbox_inches="tight"))
    finally:
        plt.close(fig)
