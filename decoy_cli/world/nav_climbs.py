"""Climbs a polygon nav mesh (CS2) connects: where one area leads to another higher or lower by
more than a step and at most a jump, across at most a small hole.

CS2's nav draws steep stairs as a column of flat areas, each a few units deep, with rises of
a step to a jump between them (de_dust2's stairs between Under A and A). The world built from
it (`nav_polygons.py`) keeps those rises as step faces; players walk the stairs. The lattice,
0.7 m apart, seldom lands a node on so narrow an area with room for the capsule, so it can miss
the way the nav names. Each climb here is the pair of nearest points of two connected areas'
outlines (metres: lower or higher end first as the connection runs), for the waypoint builder
to join where its graph goes far round (`decoy_cli/waypoints/climbs.py`).
"""

from __future__ import annotations

import numpy as np

from decoy_cli.csgo import HAMMER_TO_M
from decoy_cli.world.nav_geometry import BRIDGE_MAX_GAP_U, JUMP_U, STEP_U
from decoy_cli.world.nav_json import PolygonNav
from decoy_cli.world.world import World

OUTLINE_STEP_U = 4.0
"""Outlines are compared at points this far apart (and at every corner)."""


def world_climbs(world: World) -> np.ndarray | None:
    """The climbs a world carries (`World.meta["climbs"]`, set by `nav_climbs` for a world made
    from a polygon nav), None for a world that names none (CS:GO's, a user's mesh)."""
    climbs = world.meta.get("climbs")
    return climbs if isinstance(climbs, np.ndarray) else None


def nav_climbs(nav: PolygonNav) -> np.ndarray:
    """(C, 6) metres: for every directed connection whose two areas' outlines come within
    `BRIDGE_MAX_GAP_U` of each other, the points of the two outlines where they come nearest
    (the middle of that stretch), when the end's floor there lies more than `STEP_U` and at
    most `JUMP_U` above or below the start's; in connection order."""
    outlines = [_outline(nav.polygon(a)) for a in range(nav.num_areas)]
    climbs = []
    for a, b in nav.connections.tolist():
        start, end = outlines[a], outlines[b]
        gap = np.hypot(start[:, None, 0] - end[None, :, 0], start[:, None, 1] - end[None, :, 1])
        if gap.min() > BRIDGE_MAX_GAP_U:
            continue
        i, j = _middle_pair(start, end, gap)
        if STEP_U < abs(float(end[j, 2] - start[i, 2])) <= JUMP_U:
            climbs.append([*start[i], *end[j]])
    return np.asarray(climbs, dtype=np.float64).reshape(-1, 6) * HAMMER_TO_M


def _middle_pair(start: np.ndarray, end: np.ndarray, gap: np.ndarray) -> tuple[int, int]:
    """Of the pairs of outline points nearest each other (within `OUTLINE_STEP_U` of the least
    gap), the one nearest their middle: where two edges run side by side, the middle of the
    stretch they share, not a corner."""
    near_i, near_j = np.nonzero(gap <= gap.min() + OUTLINE_STEP_U)
    middles = (start[near_i, :2] + end[near_j, :2]) / 2
    off_middle = np.round(np.linalg.norm(middles - middles.mean(axis=0), axis=1), 3)
    k = int(np.lexsort((gap[near_i, near_j], off_middle))[0])  # then the shorter of a tie
    return int(near_i[k]), int(near_j[k])


def _outline(polygon: np.ndarray) -> np.ndarray:
    """Points along a polygon's edges, `OUTLINE_STEP_U` apart, each corner included."""
    points = []
    for a, b in zip(polygon, np.roll(polygon, -1, axis=0), strict=True):
        count = max(1, int(np.ceil(np.hypot(*(b[:2] - a[:2])) / OUTLINE_STEP_U)))
        points.append(a + (np.arange(count) / count)[:, None] * (b - a))
    return np.concatenate(points)
