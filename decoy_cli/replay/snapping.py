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

A player is at that waypoint when he lands, not at the frame: `ground_delay_s` says how much
later. Over the floor he jumped from that is no later (he is above his own path); falling to a
lower floor it is his fall from rest (an upper bound: he may be falling already). A climber
on a ladder is at no waypoint either: the first frame of a passage targets the end he left,
the last the end he reaches, each at the time the climbing speed puts him there (the delay
negative for the end he left); frames between have no target, and the plan's path between the
two ends is the ladder (`decoy_cli.replay.plans.PathCache`).
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from enum import IntEnum

import numpy as np

from decoy_cli.csgo import GRAVITY_M_S2, JUMP_HEIGHT_M, LADDER_SPEED_M_S
from decoy_cli.errors import EstaError, GraphError
from decoy_cli.waypoints.graph import WaypointGraph, in_the_air

DEFAULT_MAX_SNAP_M = 2.0
"""Farthest a position may lie from its waypoint (3-D, metres) and still snap.

The lattice spacing is 0.7 m, so a position on the graph's floors lies within about 0.5 m of a
waypoint, and a jumping player about 1.2 m; a position farther than this from every waypoint on
its floor is off the graph, and snapping it would invent a location.
"""

CLIMB_MARGIN = 1.25
"""How much faster than the climbing speed a player's height may change between two frames and
his frames on a ladder still be a climb (chosen, not measured); faster, he fell beside it."""

WITHIN_M = 0.5
"""Snap error the summary counts as good (the share of frames within it is reported)."""


class SnapStatus(IntEnum):
    """What happened to one frame when snapping."""

    SNAPPED = 0  # alive, with a position, and a waypoint on its floor
    NOT_ALIVE = 1  # dead (or absent) in this frame: nothing to snap
    NO_POSITION = 2  # alive but without a finite position in the data
    NO_WAYPOINT = 3  # no waypoint on the position's floor within the snap distance
    AIRBORNE = 4  # in the air (`in_the_air`): jumping or falling
    ON_LADDER = 5  # climbing a ladder (`WaypointGraph.on_ladders`), not at one of its ends


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
    straight under the position, or on a ladder the end of the passage's edge (-1 elsewhere,
    between a passage's first and last frame, or none within the snap distance)."""
    ground_delay_s: np.ndarray
    """(F,) float64 seconds from the frame until the player is at `ground_node` (negative: since
    he left it; 0 where there is none)."""

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
        """Alive frames in the air (`in_the_air`: jumping, falling) or climbing a ladder: not
        snapped, a player there stands at no waypoint."""
        return self.count(SnapStatus.AIRBORNE) + self.count(SnapStatus.ON_LADDER)

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
    seconds: np.ndarray | None = None,
) -> SnapResult:
    """Snap each alive frame's position (metres, shape (F, 3)) to its floor-aware nearest waypoint.

    `alive` is (F,) bool. Dead frames, frames without a finite position and positions with no
    waypoint on their floor within `max_distance` get node -1 and error NaN, with their reason.
    `floor_z` (F,), the world's floor height under each position (NaN where none is known), marks
    the frames in the air, and so does a known non-zero `vertical_speed` (F,) (m/s) with it.
    `seconds` (F,), the frame times, tell a climb from a fall beside a ladder.
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
    ladders = np.zeros((frames, len(graph.ladders)), dtype=bool)
    ladders[candidates] = graph.on_ladders(pos[candidates])
    if floor_z is not None:
        floor_z = np.asarray(floor_z, dtype=np.float64)
        if floor_z.shape != (len(pos),):
            raise EstaError(f"floor heights have shape {floor_z.shape}, expected ({len(pos)},)")
        airborne = candidates & in_the_air(pos[:, 2], floor_z, vertical_speed)
        status[airborne] = SnapStatus.AIRBORNE
        # on a ladder with no floor under him: climbing
        climbing = candidates & ~airborne & ladders.any(axis=1) & np.isnan(floor_z)
        status[climbing] = SnapStatus.ON_LADDER
        candidates &= ~airborne & ~climbing
    query = np.flatnonzero(candidates)
    if len(query):
        index, distance = graph.nearest(pos[query], max_distance=max_distance)
        found = index >= 0
        node[query[found]] = index[found]
        error[query[found]] = distance[found]
        status[query[found]] = SnapStatus.SNAPPED
        status[query[~found]] = SnapStatus.NO_WAYPOINT
    ground_node = np.full(frames, -1, dtype=np.int64)
    delay = np.zeros(frames)
    if floor_z is not None:
        in_air = np.flatnonzero((status == SnapStatus.AIRBORNE) & np.isfinite(floor_z))
        if len(in_air):
            under = pos[in_air].copy()
            under[:, 2] = floor_z[in_air]
            ground_node[in_air] = graph.nearest(under, max_distance=max_distance)[0]
            height = pos[in_air, 2] - floor_z[in_air]
            lower = floor_z[in_air] < _level_left(graph, node)[in_air] - JUMP_HEIGHT_M
            delay[in_air] = np.where(lower, np.sqrt(2 * np.maximum(height, 0) / GRAVITY_M_S2), 0)
    _ladder_targets(graph, pos, seconds, ladders, node, error, status, ground_node, delay)
    return SnapResult(node, error, status, ground_node, delay)


def _level_left(graph: WaypointGraph, node: np.ndarray) -> np.ndarray:
    """(F,) height of the waypoint of the last snapped frame up to each frame (NaN before the
    first): the floor a player in the air jumped or fell from."""
    last = np.maximum.accumulate(np.where(node >= 0, np.arange(len(node)), -1))
    return np.where(last >= 0, graph.positions[node[np.maximum(last, 0)], 2], np.nan)


def _ladder_targets(
    graph: WaypointGraph, pos: np.ndarray, seconds: np.ndarray | None, ladders: np.ndarray,
    node: np.ndarray, error: np.ndarray, status: np.ndarray, ground: np.ndarray,
    delay: np.ndarray,
) -> None:  # fmt: skip
    """Set the targets of the frames on a ladder (in place; `ladders` (F, L): which of
    `graph.ladders` each frame is on). Per passage (consecutive frames at no waypoint on a
    ladder): the ladder whose ends lie nearest the heights just before and after it (ladders
    may share an end); at its first frame the end he left, at its last the end he reached, each
    the end nearer the height before or after the passage (one end twice for a jump beside a
    ladder); one frame alone targets the end he reached. A frame next to a passage
    snapped to one of its ends but still on the ladder (between the ends' heights) is climbing,
    not there yet: it joins the passage. A passage whose height changes faster than a climb
    between two of its frames (`seconds` known) is a fall beside the ladder: left as it is."""
    unsnapped = np.isin(status, (SnapStatus.AIRBORNE, SnapStatus.NO_WAYPOINT, SnapStatus.ON_LADDER))
    frames = np.flatnonzero(unsnapped & ladders.any(axis=1))
    breaks = np.flatnonzero(np.diff(frames) != 1) + 1
    for run in np.split(frames, breaks) if len(frames) else []:
        first, last = int(run[0]), int(run[-1])
        before = _height(pos, first - 1, pos[first, 2])
        after = _height(pos, last + 1, pos[last, 2])
        k = _passage_ladder(graph, ladders[run], before, after)
        edge = int(graph.ladders[k])
        foot, top = int(graph.edge_source[edge]), int(graph.edge_target[edge])
        while first > 0 and ladders[first - 1, k] and node[first - 1] in (foot, top):
            first -= 1
        while last + 1 < len(pos) and ladders[last + 1, k] and node[last + 1] in (foot, top):
            last += 1
        if seconds is not None and _faster_than_a_climb(pos, seconds, first, last):
            continue  # a fall beside the ladder
        run = np.arange(first, last + 1)
        node[run], error[run], status[run] = -1, np.nan, SnapStatus.ON_LADDER
        ground[run], delay[run] = -1, 0.0
        low, high = graph.positions[foot, 2], graph.positions[top, 2]
        done = np.clip((pos[run, 2] - low) / (high - low), 0.0, 1.0)  # share of the climb up
        climb_s = float(graph.edge_climb_s[edge])
        # the ends nearest the heights around the passage: a climb leaves one and reaches the
        # other, a jump beside the ladder's foot leaves and reaches the foot
        left_top = abs(before - high) < abs(before - low)
        reached_top = abs(after - high) < abs(after - low)
        ground[first] = top if left_top else foot
        delay[first] = -climb_s * (1 - done[0] if left_top else done[0])
        ground[last] = top if reached_top else foot  # one frame alone: the end reached
        delay[last] = climb_s * (1 - done[-1] if reached_top else done[-1])


def _faster_than_a_climb(pos: np.ndarray, seconds: np.ndarray, first: int, last: int) -> bool:
    """Whether the height changes faster than `CLIMB_MARGIN` times the climbing speed between
    two consecutive frames of `first`..`last` or the frames just around them."""
    frames = np.arange(max(first - 1, 0), min(last + 2, len(pos)))
    frames = frames[np.isfinite(pos[frames, 2])]
    rise, took = np.abs(np.diff(pos[frames, 2])), np.diff(seconds[frames])
    return bool((rise > CLIMB_MARGIN * LADDER_SPEED_M_S * took).any())


def _passage_ladder(graph: WaypointGraph, on: np.ndarray, before: float, after: float) -> int:
    """Which of `graph.ladders` a passage whose frames are on `on` (n, L) climbs: the one most
    of them are on, then the one whose ends' heights lie nearest `before` and `after` (climbing
    up or down)."""
    low = graph.positions[graph.edge_source[graph.ladders], 2]
    high = graph.positions[graph.edge_target[graph.ladders], 2]
    mismatch = np.minimum(
        abs(before - low) + abs(after - high), abs(before - high) + abs(after - low)
    )
    missed = len(on) - on.sum(axis=0)
    return int(np.lexsort((mismatch, missed))[0])


def _height(pos: np.ndarray, frame: int, otherwise: float) -> float:
    """The height of `frame`, or `otherwise` where there is no such frame or no position."""
    known = 0 <= frame < len(pos) and np.isfinite(pos[frame, 2])
    return float(pos[frame, 2]) if known else otherwise


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
    return replace(snap, node=node, error_m=error)
