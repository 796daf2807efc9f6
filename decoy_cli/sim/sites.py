"""Bomb-site zones: where the bomb may be planted (`SiteZones`); the game's zones of de_dust2.

Split from the bomb rules (`decoy_cli.sim.rules`, which re-exports these names) because a zone
is geometry over the waypoint graph and measured data, while the rules are timing. On de_dust2
the zones are the game's bomb-target volumes measured from real rounds (see
`BOMB_TARGET_BOXES`); the nav places BombsiteA/B that name the graph's site regions cover about
twice that area. Elsewhere a zone is the space within 0.75 m horizontally and 1.5 m vertically
of a site waypoint.
"""

from __future__ import annotations

from collections.abc import Mapping
from itertools import chain

import numpy as np
from scipy.spatial import cKDTree

from decoy_cli.waypoints.graph import WaypointGraph

Box = tuple[tuple[float, ...], tuple[float, ...]]
"""An axis-aligned box: (low x, y, z), (high x, y, z), metres."""

SITE_REGIONS = {"A": "bombsite_a", "B": "bombsite_b"}
"""Bomb site name -> graph region holding its waypoints."""

ZONE_HORIZONTAL_M = 0.75
"""How far from a site waypoint, horizontally, a site zone reaches. Just over the waypoint
lattice spacing (0.70 m), so the zone has no holes between waypoints."""

ZONE_VERTICAL_M = 1.5
"""How far above or below a site waypoint a site zone reaches (a jump, stairs, a ramp)."""

_MEASURED_BOMB_TARGETS: dict[str, dict[str, Box]] = {
    "de_dust2": {
        "A": ((18.29, 44.33, 1.80), (24.08, 50.29, 3.39)),
        "B": ((-33.15, 47.24, 0.00), (-25.94, 54.41, 1.82)),
    },
}
# The bounds of every position where the bomb carrier had awpy's `isInBombZone` set (the game's
# func_bomb_target trigger; the flag is only ever set for the carrier), over the 385 real T-side
# rounds of ../shared/data/esta_dust2_tside (44,423 carrier frames, 1,854 in a zone), rounded
# outward to the centimetre. 1,854 of the 1,856 carrier frames inside those bounds are in a zone:
# the volumes are boxes. Boxes fitted on 8 of the 15 matches and tested on the other 7 (20 random
# splits) agree with the game's flag at precision 0.990 and recall 0.991 with a 0.1 m margin
# (0.999 / 0.976 without); the waypoint zones of the nav-place site regions reach recall 0.992
# but precision 0.576 (they cover twice the area). All 197 real plant positions of those rounds
# lie in the boxes (195 in the region zones), and the 18 plants of the independent OG-NaVi match
# (../shared/data/esta_dust2_events) all lie in the box of the site the game logged.

BOX_MARGIN_M = 0.1
"""Added on every side of a measured box: the data bounds where players stood, not the trigger."""

BOMB_TARGET_BOXES: dict[str, dict[str, Box]] = {
    map_name: {
        site: (
            tuple(v - BOX_MARGIN_M for v in low),
            tuple(v + BOX_MARGIN_M for v in high),
        )
        for site, (low, high) in sites.items()
    }
    for map_name, sites in _MEASURED_BOMB_TARGETS.items()
}
"""Bomb-site zones of the maps whose bomb-target volumes are known, by map name, metres."""


class SiteZones:
    """Bomb-site zones: a point is in a site if it lies inside one of the site's boxes or within
    `horizontal_m` horizontally and `vertical_m` vertically of one of its waypoints.

    Sites are tried in sorted name order; the first that holds a point names it.
    """

    def __init__(
        self,
        nodes: Mapping[str, np.ndarray] | None = None,
        boxes: Mapping[str, Box] | None = None,
        horizontal_m: float = ZONE_HORIZONTAL_M,
        vertical_m: float = ZONE_VERTICAL_M,
    ) -> None:
        nodes = dict(nodes or {})
        boxes = dict(boxes or {})
        self.names: list[str] = sorted(set(nodes) | set(boxes))
        if not self.names or any(not isinstance(n, str) or not n for n in self.names):
            raise ValueError("bomb-site zones need at least one site, named by a non-empty str")
        if not (horizontal_m > 0 and vertical_m > 0):
            raise ValueError("bomb-site zone ranges must be positive")
        self.horizontal_m = float(horizontal_m)
        self.vertical_m = float(vertical_m)
        index = {name: k for k, name in enumerate(self.names)}

        low, high, box_site = [], [], []
        for name, (lo, hi) in boxes.items():
            lo_arr = np.asarray(lo, dtype=np.float64)
            hi_arr = np.asarray(hi, dtype=np.float64)
            if lo_arr.shape != (3,) or hi_arr.shape != (3,) or not np.all(lo_arr <= hi_arr):
                raise ValueError(f"site {name!r}: a box is (low xyz, high xyz) with low <= high")
            low.append(lo_arr)
            high.append(hi_arr)
            box_site.append(index[name])
        self._box_low = np.asarray(low, dtype=np.float64).reshape(-1, 3)
        self._box_high = np.asarray(high, dtype=np.float64).reshape(-1, 3)
        self._box_site = np.asarray(box_site, dtype=np.int64)

        positions, node_site = [], []
        for name, pos in nodes.items():
            arr = np.asarray(pos, dtype=np.float64)
            if arr.ndim != 2 or arr.shape[1] != 3 or not np.all(np.isfinite(arr)):
                raise ValueError(f"site {name!r}: waypoints must be finite, shape (K, 3)")
            positions.append(arr)
            node_site.append(np.full(len(arr), index[name], dtype=np.int64))
        self._node_z = np.concatenate(positions)[:, 2] if positions else np.empty(0)
        self._node_site = np.concatenate(node_site) if node_site else np.empty(0, np.int64)
        self._tree = cKDTree(np.concatenate(positions)[:, :2]) if len(self._node_z) else None
        self._labels = np.asarray([*self.names, ""])

    @classmethod
    def from_graph(
        cls,
        graph: WaypointGraph,
        boxes: Mapping[str, Box] | None = None,
        horizontal_m: float = ZONE_HORIZONTAL_M,
        vertical_m: float = ZONE_VERTICAL_M,
    ) -> SiteZones:
        """Zones of sites A and B: the given boxes (default: the measured bomb-target boxes of
        the graph's map, if known); a site without a box uses the waypoints of its region
        (`bombsite_a`, `bombsite_b`). Pass `boxes={}` to use the regions on every map."""
        if boxes is None:
            boxes = BOMB_TARGET_BOXES.get(str(graph.meta.get("map", "")), {})
        nodes = {
            site: graph.positions[graph.region_of(region)]
            for site, region in SITE_REGIONS.items()
            if site not in boxes
        }
        return cls(nodes=nodes, boxes=boxes, horizontal_m=horizontal_m, vertical_m=vertical_m)

    def site_of(self, points: np.ndarray) -> np.ndarray:
        """Site name of every point of an (M, 3) array ("" outside every zone or not finite)."""
        pts = np.atleast_2d(np.asarray(points, dtype=np.float64))
        if pts.ndim != 2 or pts.shape[1] != 3:
            raise ValueError(f"site_of() wants points of shape (M, 3), got {pts.shape}")
        none = len(self.names)
        inside = np.all(
            (pts[:, None, :] >= self._box_low[None]) & (pts[:, None, :] <= self._box_high[None]),
            axis=2,
        )
        best = np.where(inside, self._box_site[None, :], none).min(axis=1, initial=none)
        if self._tree is not None:
            rows = np.nonzero(np.all(np.isfinite(pts), axis=1))[0]
            hits = self._tree.query_ball_point(pts[rows, :2], r=self.horizontal_m)
            counts = np.fromiter(map(len, hits), dtype=np.int64, count=len(hits))
            cols = np.fromiter(chain.from_iterable(hits), dtype=np.int64, count=int(counts.sum()))
            rows = np.repeat(rows, counts)
            near = np.abs(self._node_z[cols] - pts[rows, 2]) <= self.vertical_m
            np.minimum.at(best, rows[near], self._node_site[cols[near]])
        return self._labels[best]
