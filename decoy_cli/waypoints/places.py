"""The nav place (the map's named areas: "BombsiteA", "Catwalk", ...) of any position."""

from __future__ import annotations

import numpy as np

from decoy_cli.waypoints.graph import WaypointGraph

NO_PLACE = "(no place)"


def place_names(graph: WaypointGraph) -> list[str]:
    """The place labels of the per-place counts: the graph's places, then `NO_PLACE`."""
    return [*graph.place_names, NO_PLACE]


class PlaceFinder:
    """The nav place of positions: the place of the nearest waypoint on the position's floor,
    or, for a position with no waypoint on its floor, of the nearest waypoint in x-y."""

    def __init__(self, graph: WaypointGraph) -> None:
        from scipy.spatial import cKDTree

        self.graph = graph
        self.names = place_names(graph)
        self._place = np.where(graph.node_place < 0, len(self.names) - 1, graph.node_place)
        self._tree_xy = cKDTree(graph.positions[:, :2])

    def find(self, points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(place index into `names`, whether a waypoint is on the point's floor) per point."""
        if not len(points):
            return np.zeros(0, np.int64), np.zeros(0, bool)
        nodes, _ = self.graph.nearest(points)
        on_floor = nodes >= 0
        if not on_floor.all():
            _, nodes[~on_floor] = self._tree_xy.query(points[~on_floor, :2])
        return self._place[nodes].astype(np.int64), on_floor
