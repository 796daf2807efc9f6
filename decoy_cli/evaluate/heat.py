"""The fixed x-y grid over a map on which a round's positions are counted (heatmaps), and the
compact sparse encoding of those counts that a cached round record keeps.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from decoy_cli.world.navmesh import load_navmesh

HEAT_CELL_M = 0.5
"""Side of a heatmap cell (metres)."""


@dataclass(frozen=True)
class HeatGrid:
    """A fixed x-y grid over the map (metres): cell (i, j) spans x0 + i·cell, y0 + j·cell."""

    x0: float
    y0: float
    cell: float
    nx: int
    ny: int

    @classmethod
    def for_map(cls, map_name: str, cell: float = HEAT_CELL_M) -> HeatGrid:
        """The grid covering every nav area of a built-in map, one cell of margin."""
        from decoy_cli.csgo import HAMMER_TO_M

        nav = load_navmesh(map_name)
        x_lo = math.floor(float(nav.x_min.min()) * HAMMER_TO_M / cell) - 1
        y_lo = math.floor(float(nav.y_min.min()) * HAMMER_TO_M / cell) - 1
        x_hi = math.ceil(float(nav.x_max.max()) * HAMMER_TO_M / cell) + 1
        y_hi = math.ceil(float(nav.y_max.max()) * HAMMER_TO_M / cell) + 1
        return cls(x0=x_lo * cell, y0=y_lo * cell, cell=cell, nx=x_hi - x_lo, ny=y_hi - y_lo)

    @property
    def size(self) -> int:
        return self.nx * self.ny

    @property
    def extent(self) -> tuple[float, float, float, float]:
        """(x_min, x_max, y_min, y_max) of the grid, for imshow."""
        return (
            self.x0,
            self.x0 + self.nx * self.cell,
            self.y0,
            self.y0 + self.ny * self.cell,
        )


def grid_sums(grid: HeatGrid, points: np.ndarray, weights: np.ndarray | None = None) -> bytes:
    """Sparse per-cell sample counts of x-y points on the grid, and with integer `weights`
    their per-cell sums: uint32 distinct flat cell indices, counts[, sums], little-endian.
    Points outside the grid are left out."""
    i = np.floor((points[:, 0] - grid.x0) / grid.cell).astype(np.int64)
    j = np.floor((points[:, 1] - grid.y0) / grid.cell).astype(np.int64)
    inside = (i >= 0) & (i < grid.nx) & (j >= 0) & (j < grid.ny)
    cells, inverse, counts = np.unique(
        j[inside] * grid.nx + i[inside], return_inverse=True, return_counts=True
    )
    parts = [cells, counts]
    if weights is not None:
        sums = np.bincount(inverse, weights=np.asarray(weights)[inside], minlength=len(cells))
        parts.append(sums.astype(np.int64))
    return b"".join(part.astype("<u4").tobytes() for part in parts)


def read_grid_sums(data: bytes, columns: int = 2) -> list[np.ndarray]:
    """The int64 arrays of a `grid_sums` encoding: cells, counts (and sums: `columns` = 3)."""
    values = np.frombuffer(data, dtype="<u4").astype(np.int64)
    return list(values.reshape(columns, -1))
