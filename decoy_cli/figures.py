"""Pieces every figure shares: the map drawn from the nav areas, and saving a PNG atomically.

matplotlib is imported inside the functions (headless Agg backend), so commands that draw
nothing do not pay for it.
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Protocol

import numpy as np

from decoy_cli.csgo import HAMMER_TO_M
from decoy_cli.files import write_atomic

if TYPE_CHECKING:
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure


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


def save_figure(fig: Figure, path: str | Path, dpi: int = 130) -> None:
    """Save a matplotlib figure as PNG (atomically) and close it."""
    import matplotlib.pyplot as plt

    try:
        write_atomic(path, lambda tmp: fig.savefig(tmp, format="png", dpi=dpi, bbox_inches="tight"))
    finally:
        plt.close(fig)
