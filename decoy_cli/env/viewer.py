"""The environment's picture: a top-down matplotlib view of a round, drawn without a screen.

Kept apart from the environment's logic (as Jumanji keeps its viewers): the environment asks it
for an RGB array and knows nothing of matplotlib.
"""

from __future__ import annotations

from typing import ClassVar

import numpy as np

from decoy_cli.sim.state import Agents, Bomb, BombStatus
from decoy_cli.waypoints.graph import WaypointGraph


class TopDownView:
    """A matplotlib figure of the map drawn once; each render moves the agents and the bomb."""

    SIZE_PX = 512
    COLOURS: ClassVar[dict[str, tuple[float, float, float, float]]] = {
        "T": (0.93, 0.55, 0.13, 1.0),
        "CT": (0.16, 0.38, 0.85, 1.0),
        "dead": (0.8, 0.8, 0.8, 1.0),
    }

    def __init__(self, graph: WaypointGraph, sides: list[str]) -> None:
        from matplotlib.backends.backend_agg import FigureCanvasAgg
        from matplotlib.figure import Figure

        figure = Figure(figsize=(self.SIZE_PX / 100, self.SIZE_PX / 100), dpi=100)
        self.canvas = FigureCanvasAgg(figure)
        axes = figure.add_axes((0.0, 0.0, 1.0, 1.0))
        axes.set_axis_off()
        axes.set_aspect("equal")
        xy = graph.positions[:, :2]
        axes.scatter(xy[:, 0], xy[:, 1], s=0.5, c="0.7", linewidths=0)
        lo, hi = xy.min(axis=0) - 1.0, xy.max(axis=0) + 1.0
        axes.set_xlim(lo[0], hi[0])
        axes.set_ylim(lo[1], hi[1])
        self.sides = np.asarray(sides)
        count = len(sides)
        self.agents = axes.scatter(
            np.zeros(count), np.zeros(count), s=60, edgecolors="black", linewidths=0.8, zorder=3
        )
        self.bomb = axes.scatter([], [], marker="*", s=180, c="red", edgecolors="black", zorder=4)

    def draw(self, agents: Agents, bomb: Bomb | None) -> np.ndarray:
        colours = np.array([self.COLOURS[str(side)] for side in self.sides])
        colours[~agents.alive] = self.COLOURS["dead"]
        self.agents.set_offsets(agents.position[:, :2])
        # (set_facecolors is an alias the stubs lack; they also lack (N, 4) RGBA arrays)
        self.agents.set_facecolor(colours)  # type: ignore[arg-type]
        if bomb is None or (bomb.status == BombStatus.CARRIED and bomb.carrier < 0):
            self.bomb.set_offsets(np.empty((0, 2)))
        else:
            self.bomb.set_offsets(bomb.position[None, :2])
        self.canvas.draw()
        return np.asarray(self.canvas.buffer_rgba())[..., :3].copy()
