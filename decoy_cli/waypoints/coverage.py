"""How much of a map's walkable floor a waypoint graph covers, by area.

The nav mesh's areas are the floor the game says players can walk on. Each area is sampled on a
regular grid (every sample stands for an equal patch of floor, so shares are shares by area) at
the height of the world's bilinear floor, and a sample counts as covered when a waypoint on its
floor lies within `ALIGNED_WITHIN_M` in 3-D (the graph's floor-aware nearest waypoint). A built
graph keeps only its largest strongly connected component, so this is that component's coverage.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from decoy_cli.csgo import HAMMER_TO_M
from decoy_cli.waypoints.graph import WaypointGraph
from decoy_cli.waypoints.quality import ALIGNED_WITHIN_M
from decoy_cli.world.nav_geometry import floor_corner_heights
from decoy_cli.world.navmesh import NavMesh

SAMPLE_SPACING_U = 8.0
"""Grid spacing of the floor samples (about 0.15 m, a fifth of the lattice spacing)."""


@dataclass(frozen=True)
class NavCoverage:
    """Covered share of the nav mesh's floor area, overall and per place (shares in [0, 1])."""

    area_m2: float
    covered: float
    by_place: dict[str, float]  # place ("" for unnamed areas) -> covered share of its area

    def worst_places(self, count: int = 5) -> list[tuple[str, float]]:
        return sorted(self.by_place.items(), key=lambda kv: kv[1])[:count]


def floor_samples(nav: NavMesh) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Grid samples of every nav area's floor: (points (M, 3) metres, area index (M,), the floor
    area each sample stands for (M,) square metres)."""
    zx, zy = floor_corner_heights(nav)
    points, owner, weight = [], [], []
    for a in range(nav.num_areas):
        width, depth = nav.x_max[a] - nav.x_min[a], nav.y_max[a] - nav.y_min[a]
        nx, ny = (
            max(1, int(np.ceil(width / SAMPLE_SPACING_U))),
            max(1, int(np.ceil(depth / SAMPLE_SPACING_U))),
        )
        grid_u, grid_v = np.meshgrid((np.arange(nx) + 0.5) / nx, (np.arange(ny) + 0.5) / ny)
        u, v = grid_u.ravel(), grid_v.ravel()
        z = (
            nav.z_at_min[a] * (1 - u) * (1 - v)
            + zx[a] * u * (1 - v)
            + zy[a] * (1 - u) * v
            + nav.z_at_max[a] * u * v
        )
        x = nav.x_min[a] + u * width
        y = nav.y_min[a] + v * depth
        points.append(np.column_stack([x, y, z]))
        owner.append(np.full(len(u), a, dtype=np.int64))
        weight.append(np.full(len(u), width * depth / len(u)))
    return (
        np.concatenate(points) * HAMMER_TO_M,
        np.concatenate(owner),
        np.concatenate(weight) * HAMMER_TO_M**2,
    )


def nav_coverage(graph: WaypointGraph, nav: NavMesh) -> NavCoverage:
    """The share of the nav mesh's floor area within reach of a waypoint of the graph."""
    points, owner, weight = floor_samples(nav)
    index, _ = graph.nearest(points, max_distance=ALIGNED_WITHIN_M)
    covered = index >= 0
    places = nav.place[owner]
    by_place = {
        str(place): float(weight[covered & (places == place)].sum() / weight[places == place].sum())
        for place in np.unique(places)
    }
    return NavCoverage(
        area_m2=float(weight.sum()),
        covered=float(weight[covered].sum() / weight.sum()),
        by_place=by_place,
    )
