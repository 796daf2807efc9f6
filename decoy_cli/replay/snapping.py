"""Snap one player's data-frame positions to waypoints, floor-aware and vectorised.

Every alive frame with a position is looked up in one batched `WaypointGraph.nearest` call, so a
player on the upper floor of a two-floor spot never snaps to the floor below. Frames that cannot
be snapped keep node -1 and error NaN, and say why in `status`, so they are counted, never
silently dropped.

Given the height of the world's floor under each position, frames more than `AIRBORNE_M` above
it (a jump, a fall off a ledge), and frames whose vertical speed is known and not zero (awpy's
velocityZ: the Source engine keeps none on the ground), are not snapped either: a player in the
air is at no waypoint, and the floor-aware lookup would put it on whatever lower floor lies
nearest (a box beside the fall), a target the replay then has to detour to. Such a frame gets
instead the waypoint nearest the spot on the floor straight under it (`ground_node`), a target
the plan uses only where it keeps the replay in time (`decoy_cli.replay.rounds.plan_player`);
elsewhere the plan goes through those frames on the path between the frames before and after.
"""

from __future__ import annotations

from dataclasses import dataclass
from enum import IntEnum

import numpy as np

from decoy_cli.errors import EstaError, GraphError
from decoy_cli.waypoints.graph import WaypointGraph, in_the_air

DEFAULT_MAX_SNAP_M = 2.0
"""Farthest a position may lie from its waypoint (3-D, metres) and still snap.

The lattice spacing is 0.7 m, so a position on the graph's floors lies within about 0.5 m of a
waypoint, and a jumping player about 1.2 m; a position farther than this from every waypoint on
its floor is off the graph, and snapping it would invent a location.
"""

WITHIN_M = 0.5
"""Snap error the summary counts as good (the share of frames within it is reported)."""


class SnapStatus(IntEnum):
    """What happened to one frame when snapping."""

    SNAPPED = 0  # alive, with a position, and a waypoint on its floor
    NOT_ALIVE = 1  # dead (or absent) in this frame: nothing to snap
    NO_POSITION = 2  # alive but without a finite position in the data
    NO_WAYPOINT = 3  # no waypoint on the position's floor within the snap distance
    AIRBORNE = 4  # in the air (`in_the_air`): jumping or falling


@dataclass(frozen=True)
class SnapResult:
    """Snapped waypoint of every data frame of one player."""

    node: np.ndarray
    """(F,) int64 waypoint index per frame, -1 where not snapped."""
    error_m: np.ndarray
    """(F,) float64 3-D distance from the position to its waypoint, NaN where not snapped."""
    status: np.ndarray
    """(F,) int8 `SnapStatus` per frame: why a frame was or was not snapped."""
    ground_node: np.ndarray
    """(F,) int64 for frames in the air: the waypoint nearest the spot on the world's floor
    straight under the position, or on a ladder the end of its edge nearest in height (-1
    elsewhere, or none within the snap distance)."""

    def count(self, status: SnapStatus) -> int:
        """Number of frames with this status."""
        return int(np.count_nonzero(self.status == status))

    @property
    def num_snapped(self) -> int:
        """Frames snapped to a waypoint."""
        return self.count(SnapStatus.SNAPPED)

    @property
    def num_unsnappable(self) -> int:
        """Alive frames whose position has no waypoint on its floor within the snap distance."""
        return self.count(SnapStatus.NO_WAYPOINT)

    @property
    def num_airborne(self) -> int:
        """Alive frames in the air (`in_the_air`: jumping, falling): not snapped, a player in
        the air stands at no waypoint."""
        return self.count(SnapStatus.AIRBORNE)

    def counts(self) -> dict[str, int]:
        """Frame count per status name (for example {'SNAPPED': 120, 'NOT_ALIVE': 13, ...})."""
        return {status.name: self.count(status) for status in SnapStatus}


def snap_positions(
    graph: WaypointGraph,
    positions: np.ndarray,
    alive: np.ndarray,
    max_distance: float = DEFAULT_MAX_SNAP_M,
    floor_z: np.ndarray | None = None,
    vertical_speed: np.ndarray | None = None,
) -> SnapResult:
    """Snap each alive frame's position (metres, shape (F, 3)) to its floor-aware nearest waypoint.

    `alive` is (F,) bool. Dead frames, frames without a finite position and positions with no
    waypoint on their floor within `max_distance` get node -1 and error NaN, with their reason.
    `floor_z` (F,), the world's floor height under each position (NaN where none is known), marks
    the frames in the air, and so does a known non-zero `vertical_speed` (F,) (m/s) with it.
    """
    pos = np.asarray(positions, dtype=np.float64)
    alive = np.asarray(alive, dtype=bool)
    if pos.ndim != 2 or pos.shape[1] != 3:
        raise EstaError(f"player positions have shape {pos.shape}, expected (frames, 3)")
    if alive.shape != (len(pos),):
        raise EstaError(f"alive flags have shape {alive.shape}, expected ({len(pos)},)")
    if graph.num_nodes == 0:
        raise GraphError("the waypoint graph has no waypoints")

    frames = len(pos)
    node = np.full(frames, -1, dtype=np.int64)
    error = np.full(frames, np.nan)
    status = np.full(frames, SnapStatus.NOT_ALIVE, dtype=np.int8)
    finite = np.isfinite(pos).all(axis=1)
    status[alive & ~finite] = SnapStatus.NO_POSITION

    candidates = alive & finite
    if floor_z is not None:
        floor_z = np.asarray(floor_z, dtype=np.float64)
        if floor_z.shape != (len(pos),):
            raise EstaError(f"floor heights have shape {floor_z.shape}, expected ({len(pos)},)")
        airborne = candidates & in_the_air(pos[:, 2], floor_z, vertical_speed)
        status[airborne] = SnapStatus.AIRBORNE
        candidates &= ~airborne
    query = np.flatnonzero(candidates)
    if len(query):
        index, distance = graph.nearest(pos[query], max_distance=max_distance)
        found = index >= 0
        node[query[found]] = index[found]
        error[query[found]] = distance[found]
        status[query[found]] = SnapStatus.SNAPPED
        status[query[~found]] = SnapStatus.NO_WAYPOINT
    ground_node = np.full(frames, -1, dtype=np.int64)
    if floor_z is not None:
        in_air = np.flatnonzero((status == SnapStatus.AIRBORNE) & np.isfinite(floor_z))
        if len(in_air):
            under = pos[in_air].copy()
            under[:, 2] = floor_z[in_air]
            index, _ = graph.nearest(under, max_distance=max_distance)
            ladder = graph.ladder_end(pos[in_air])  # a climber heads for the ladder's ends
            ground_node[in_air] = np.where(ladder >= 0, ladder, index)
    return SnapResult(node=node, error_m=error, status=status, ground_node=ground_node)


def snap_into_sites(
    graph: WaypointGraph,
    snap: SnapResult,
    positions: np.ndarray,
    sites: np.ndarray,
    node_site: np.ndarray,
    max_distance: float = DEFAULT_MAX_SNAP_M,
) -> SnapResult:
    """Re-snap the frames where `sites` (F,) names a bomb site to the nearest waypoint inside
    that site's zone (`node_site`, the site of every waypoint, "" outside every zone).

    A player standing just inside a zone's edge may have its nearest waypoint just outside, and
    a carrier there could not plant where the real one did: the lattice's 0.7 m spacing must not
    move a plant out of its site. Frames already on a waypoint of their site, or with none of
    its waypoints within `max_distance`, keep their snap.
    """
    node, error = snap.node.copy(), snap.error_m.copy()
    snapped = snap.status == SnapStatus.SNAPPED
    wrong = np.flatnonzero((sites != "") & snapped & (node_site[np.maximum(node, 0)] != sites))
    for f in wrong:
        inside = np.flatnonzero(node_site == sites[f])
        if not len(inside):
            continue
        distance = np.linalg.norm(graph.positions[inside] - positions[f], axis=1)
        best = int(np.argmin(distance))
        if distance[best] <= max_distance:
            node[f], error[f] = inside[best], distance[best]
    return SnapResult(node=node, error_m=error, status=snap.status, ground_node=snap.ground_node)
