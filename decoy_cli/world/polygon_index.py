"""The floors and edges of a polygon nav mesh (CS2), indexed for the world built from it
(`nav_polygons.py`): which areas lie under a point and at what height (`Floors`), and every
polygon edge with its direction and outward normal (`Edges`).
"""

from __future__ import annotations

from collections import defaultdict

import numpy as np

from decoy_cli.world.nav_geometry import TOUCH_TOL_U
from decoy_cli.world.nav_json import PolygonNav

GRID_U = 64.0
"""Cell size of the index that finds the areas under a point."""


class Floors:
    """The floor triangles of every area, and the areas and heights under a point."""

    def __init__(self, nav: PolygonNav) -> None:
        tris, owner = [], []
        for a in range(nav.num_areas):
            for tri in triangulate(nav.polygon(a)):
                tris.append(tri)
                owner.append(a)
        self.triangles = np.asarray(tris, dtype=np.float64)
        self.owner = np.asarray(owner, dtype=np.int64)
        self.cells: dict[tuple[int, int], list[int]] = defaultdict(list)
        low = np.floor(self.triangles[:, :, :2].min(axis=1) / GRID_U).astype(int)
        high = np.floor(self.triangles[:, :, :2].max(axis=1) / GRID_U).astype(int)
        for t in range(len(self.triangles)):
            for i in range(low[t, 0], high[t, 0] + 1):
                for j in range(low[t, 1], high[t, 1] + 1):
                    self.cells[(i, j)].append(t)

    def under(self, x: float, y: float) -> list[tuple[int, float]]:
        """(area, floor height) of every area whose floor lies under the point (x, y)."""
        found = []
        for t in self.cells.get((int(np.floor(x / GRID_U)), int(np.floor(y / GRID_U))), []):
            z = _height_in(self.triangles[t], x, y)
            if z is not None:
                found.append((int(self.owner[t]), z))
        return found


def triangulate(polygon: np.ndarray) -> list[np.ndarray]:
    """Triangles of a convex (or nearly convex) polygon, dropping degenerate ones; a
    quadrilateral is cut along the diagonal that leaves both halves turning the same way."""
    n = len(polygon)
    if n == 4 and (_twice_area(polygon[[0, 1, 2]]) <= 0 or _twice_area(polygon[[0, 2, 3]]) <= 0):
        polygon = polygon[[1, 2, 3, 0]]
    tris = [polygon[[0, k, k + 1]] for k in range(1, n - 1)]
    return [t for t in tris if _twice_area(t) > 1e-3]


def _twice_area(tri: np.ndarray) -> float:
    (x0, y0), (x1, y1), (x2, y2) = tri[:, :2]
    return float((x1 - x0) * (y2 - y0) - (x2 - x0) * (y1 - y0))


def _height_in(tri: np.ndarray, x: float, y: float, tol: float = 1e-6) -> float | None:
    """Height of the triangle's plane at (x, y) when the point lies in it (seen from above)."""
    (x0, y0, z0), (x1, y1, z1), (x2, y2, z2) = tri
    det = (y1 - y2) * (x0 - x2) + (x2 - x1) * (y0 - y2)
    if abs(det) < 1e-9:
        return None
    l0 = ((y1 - y2) * (x - x2) + (x2 - x1) * (y - y2)) / det
    l1 = ((y2 - y0) * (x - x2) + (x0 - x2) * (y - y2)) / det
    l2 = 1 - l0 - l1
    if min(l0, l1, l2) < -tol:
        return None
    return float(l0 * z0 + l1 * z1 + l2 * z2)


class Edges:
    """Every polygon edge: start, direction, length, outward normal (seen from above)."""

    def __init__(self, nav: PolygonNav) -> None:
        start, end, area = [], [], []
        for a in range(nav.num_areas):
            poly = nav.polygon(a)
            for k in range(len(poly)):
                p, q = poly[k], poly[(k + 1) % len(poly)]
                if np.hypot(*(q - p)[:2]) > TOUCH_TOL_U:
                    start.append(p)
                    end.append(q)
                    area.append(a)
        self.start = np.asarray(start)
        self.end = np.asarray(end)
        self.area = np.asarray(area, dtype=np.int64)
        delta = (self.end - self.start)[:, :2]
        self.length = np.hypot(delta[:, 0], delta[:, 1])
        self.direction = delta / self.length[:, None]
        self.normal = np.stack([self.direction[:, 1], -self.direction[:, 0]], axis=1)
        self.count = len(self.area)

    def point(self, e: int, t: float, out: float = 0.0) -> np.ndarray:
        """(x, y, z) at `t` along edge e (z on the edge), moved `out` along its normal."""
        s = t / self.length[e]
        p = self.start[e] + s * (self.end[e] - self.start[e])
        return np.array([*(p[:2] + out * self.normal[e]), p[2]])
