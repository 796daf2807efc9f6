"""The triangles of a polygon nav mesh (CS2): floors, step faces, and what stands at each open
edge (a wall, a ledge, the foot of a box, or floor across a small hole).

The same rules as the CS:GO rectangle world (`nav_geometry.py`, whose constants it shares, and
`navmesh.py`, which says why each exists), on convex polygons with a height at every corner:

* **Floors.** Each area's polygon, triangulated; no heights to fit.
* **Shared edges.** Stretches where two areas' edges lie on one line (within 1 u) join their
  floors, with a step face where the heights differ, except where the lower floor goes on
  under the upper one (a walkway over a passage).
* **Open edges.** The rest of every edge is cut into pieces of at most `PIECE_U`; each piece
  looks outward along its normal for the nearest other area within the last of `PROBES_U`
  (CS:GO's `LEDGE_REACH_U`) and gets: nothing near: a wall `POLYGON_WALL_PUSH_U` beyond the
  edge (where the nav stops short of the real walls), full height, capped below any floor
  overhead, left out where it would stand on another floor of the same level; an area within
  a jump in height across a gap of at most `BRIDGE_MAX_GAP_U` (looked for first, so that a
  floor far below the gap does not hide it): floor to the gap's middle (a hole in the mesh),
  square past the edge's ends so that the holes where corners meet close too, and closed by
  a face from the higher side; one of that level farther than
  `SAME_LEVEL_REACH_U`: a wall, as for nothing near; any other area near (higher or lower):
  floor to the push, then a face between the two heights (a ledge to drop from, the
  foot of a box to jump onto), none where that face would hang into a passage under a
  walkway. Every open piece's floor runs on under its push.
* **Corners.** Where two walls meet at a corner of the open boundary, a wall joins their ends
  so that no gap opens at the corner.
"""

from __future__ import annotations

from collections import defaultdict
from collections.abc import Iterator
from itertools import pairwise
from pathlib import Path

import numpy as np

from decoy_cli.csgo import HAMMER_TO_M
from decoy_cli.world.nav_climbs import nav_climbs
from decoy_cli.world.nav_geometry import (
    BRIDGE_MAX_GAP_U,
    JUMP_U,
    MAX_SHARED_STEP_U,
    STEP_U,
    TOUCH_TOL_U,
    WALL_HEIGHT_U,
    quad,
    subtract,
)
from decoy_cli.world.nav_json import PolygonNav
from decoy_cli.world.polygon_index import Edges, Floors
from decoy_cli.world.world import World

PIECE_U = 16.0
"""Open edges are judged piece by piece, each at most this long."""
PROBES_U = (1.0, 4.0, 8.0, 16.0, 24.0, 32.0, 40.0, 48.0, 64.0, 80.0, 96.0, 112.0, 128.0)
"""Distances beyond an open piece at which other areas are looked for."""
POLYGON_WALL_PUSH_U = 24.0
"""How far walls stand beyond an open edge: measured, the median distance from the CS2
de_dust2 nav's open edges to the walls of the brush mesh of ../shared/data/meshes
(benchmarks/studies/cs2_world.py), where CS:GO's nav stops `WALL_PUSH_U` short."""
SAME_LEVEL_REACH_U = 2 * POLYGON_WALL_PUSH_U
"""A floor of the same level (within a jump) farther beyond an open edge than this has a wall
between: both stop that far short of it (CS:GO's world counts three of its pushes)."""
OVERHEAD_U = 72.0
"""A floor more than this above a wall's foot is a floor overhead: the wall stops below it."""

CornerNotes = dict[tuple[float, float], list[tuple[str, np.ndarray, float, float]]]
"""Per corner of the open boundary (x, y rounded), the wall pieces that start or end there:
("starts" or "ends", the piece's end beyond the edge, the corner's height, the wall's top)."""

POLYGON_NAV_KIND = "polygon-nav"
"""`World.meta["kind"]` of a world made from a polygon nav mesh."""


def polygon_world(nav: PolygonNav, map_name: str) -> World:
    """The triangle world of a polygon nav mesh of a map, in metres."""
    return World(
        triangles=polygon_triangles(nav) * HAMMER_TO_M,
        name=map_name,
        source=f"CS2 {map_name} nav mesh ({Path(nav.source).name}, nav version {nav.version})",
        meta={
            "kind": POLYGON_NAV_KIND,
            "areas": nav.num_areas,
            "ladder_links": nav.ladder_links,
            "climbs": nav_climbs(nav),
        },
    )


def polygon_triangles(nav: PolygonNav) -> np.ndarray:
    """Floors, step faces and open-edge faces of a polygon nav mesh, (T, 3, 3) Hammer units."""
    floors = Floors(nav)
    edges = Edges(nav)
    covered, tris = _shared_stretches(edges, floors)
    walls: CornerNotes = defaultdict(list)
    for e, t0, t1, found in _open_pieces(edges, floors, covered):
        tris += _piece_faces(edges, floors, e, t0, t1, found, walls)
    tris += _corner_walls(walls)
    floor_tris = floors.triangles.reshape(-1, 3, 3)
    faces = np.asarray(tris, dtype=np.float64).reshape(-1, 3, 3)
    return np.concatenate([floor_tris, faces])


# ---- shared edges ---------------------------------------------------------------------------


def _shared_stretches(edges: Edges, floors: Floors) -> tuple[list[list], list]:
    """Per edge, the stretches [lo, hi] (along it) that another area's edge lies on, and the
    step faces of those where the two floors differ in height (made once per pair)."""
    covered: list[list[tuple[float, float]]] = [[] for _ in range(edges.count)]
    tris: list = []
    (sx, sy), (ex, ey) = edges.start[:, :2].T, edges.end[:, :2].T
    for first in range(0, edges.count, 256):
        rows = slice(first, min(first + 256, edges.count))
        x0, y0 = sx[rows, None], sy[rows, None]
        (nx, ny), (dx, dy) = edges.normal[rows].T[:, :, None], edges.direction[rows].T[:, :, None]
        rsx, rsy, rex, rey = sx - x0, sy - y0, ex - x0, ey - y0  # the others' ends, from e's start
        off = np.maximum(np.abs(rsx * nx + rsy * ny), np.abs(rex * nx + rey * ny))
        t0, t1 = rsx * dx + rsy * dy, rex * dx + rey * dy
        lo = np.maximum(np.minimum(t0, t1), 0.0)
        hi = np.minimum(np.maximum(t0, t1), edges.length[rows, None])
        ok = (off <= TOUCH_TOL_U) & (hi - lo > TOUCH_TOL_U)
        ok &= edges.area[rows, None] != edges.area[None, :]
        for i, j in zip(*np.nonzero(ok), strict=True):
            e = first + int(i)
            a_lo, a_hi = float(lo[i, j]), float(hi[i, j])
            za = [edges.point(e, t)[2] for t in (a_lo, a_hi)]
            zb = [_z_on_edge(edges, int(j), edges.point(e, t)) for t in (a_lo, a_hi)]
            if abs((za[0] + za[1]) - (zb[0] + zb[1])) / 2 > MAX_SHARED_STEP_U:
                continue  # floors far apart in height only look touching from above
            covered[e].append((a_lo, a_hi))
            rise = max(abs(za[0] - zb[0]), abs(za[1] - zb[1]))
            if rise > OVERHEAD_U and _lower_goes_under(edges, floors, e, int(j), a_lo, a_hi):
                continue
            if edges.area[e] < edges.area[j] and rise > 1:
                p0, p1 = edges.point(e, a_lo), edges.point(e, a_hi)
                low = ((*p0[:2], za[0]), (*p1[:2], za[1]))
                tris += quad(*low, (*p1[:2], zb[1]), (*p0[:2], zb[0]))
    return covered, tris


def _lower_goes_under(edges: Edges, floors: Floors, e: int, f: int, lo: float, hi: float) -> bool:
    """True where edges e and f meet far apart in height and the lower floor goes on under the
    upper one across their line (a walkway over a passage): no face stands there."""
    mid = edges.point(e, (lo + hi) / 2)
    z_e, z_f = float(mid[2]), _z_on_edge(edges, f, mid)
    into_upper = -PROBES_U[1] if z_e > z_f else PROBES_U[1]  # e's inside, or f's (e's outside)
    upper, low = (edges.area[e], z_f) if z_e > z_f else (edges.area[f], z_e)
    x, y, _ = edges.point(e, (lo + hi) / 2, into_upper)
    return _floor_near(floors, x, y, low, upper)


def _floor_near(floors: Floors, x: float, y: float, z: float, left_out: int) -> bool:
    """Whether a floor within a jump of height `z` lies under (x, y), the area `left_out`'s
    aside: the test for a lower floor going on beneath an upper one."""
    return any(area != left_out and abs(h - z) <= JUMP_U for area, h in floors.under(x, y))


def _z_on_edge(edges: Edges, e: int, point: np.ndarray) -> float:
    """Height of edge e at the point of it nearest to `point` (seen from above)."""
    along = np.dot(point[:2] - edges.start[e, :2], edges.direction[e])
    t = float(np.clip(along, 0, edges.length[e]))
    return float(edges.point(e, t)[2])


# ---- open edges ---------------------------------------------------------------------------


def _beyond(edges: Edges, floors: Floors, e: int, t: float, z: float) -> tuple[float, float] | None:
    """(gap, height) of the nearest other floor beyond edge e at `t` within reach, or None.
    A floor within a jump of `z` across a hole (at most `BRIDGE_MAX_GAP_U`) comes first, even
    where a floor far below shows sooner: the hole's far side, not the pit under it."""
    level = _first_floor(edges, floors, e, t, z, JUMP_U, BRIDGE_MAX_GAP_U)
    return level or _first_floor(edges, floors, e, t, z, MAX_SHARED_STEP_U, PROBES_U[-1])


def _first_floor(
    edges: Edges, floors: Floors, e: int, t: float, z: float, within: float, reach: float
) -> tuple[float, float] | None:
    """(gap, height) of the nearest other area's floor beyond edge e at `t`, up to `reach`
    out, among those at most `within` from height `z` (the closest in height where several)."""
    own = edges.area[e]

    def nearest_floor(distance: float) -> float | None:
        x, y, _ = edges.point(e, t, distance)
        near = [(abs(h - z), h) for a, h in floors.under(x, y) if a != own]
        near = [(dz, h) for dz, h in near if dz <= within]
        return min(near)[1] if near else None

    before = 0.0
    for distance in (d for d in PROBES_U if d <= reach):
        height = nearest_floor(distance)
        if height is not None:
            for _ in range(5):  # where the floor begins, to a thirty-second of the step
                middle = (before + distance) / 2
                found = nearest_floor(middle)
                before, distance = (before, middle) if found is not None else (middle, distance)
                height = found if found is not None else height
            return distance, height
        before = distance
    return None


def _open_pieces(
    edges: Edges, floors: Floors, covered: list[list[tuple[float, float]]]
) -> Iterator[tuple[int, float, float, tuple[float, float] | None]]:
    """Every open piece of every edge, at most `PIECE_U` long: (edge, t0, t1, beyond), where
    `beyond` is the (gap, height) of the nearest other floor beyond the piece's middle, None
    where there is none within reach."""
    for e in range(edges.count):
        for lo, hi in subtract((0.0, edges.length[e]), covered[e]):
            cuts = np.linspace(lo, hi, max(1, int(np.ceil((hi - lo) / PIECE_U))) + 1)
            for t0, t1 in pairwise(cuts):
                mid = (t0 + t1) / 2
                beyond = _beyond(edges, floors, e, mid, float(edges.point(e, mid)[2]))
                yield e, float(t0), float(t1), beyond


def _piece_faces(
    edges: Edges,
    floors: Floors,
    e: int,
    t0: float,
    t1: float,
    found: tuple[float, float] | None,
    walls: CornerNotes,
) -> list:
    """Faces of the open piece [t0, t1] of edge e by what lies beyond it (module docstring);
    its wall's ends at the edge's corners are noted in `walls` for `_corner_walls`."""
    mid = (t0 + t1) / 2
    z0, z1, zm = (float(edges.point(e, t)[2]) for t in (t0, t1, mid))
    if found is not None and abs(found[1] - zm) <= JUMP_U and found[0] > SAME_LEVEL_REACH_U:
        found = None  # a floor of this level so far off has a wall between
    if found is None:
        top = _wall_top(edges, floors, e, mid, zm)
        tris = _strip(edges, e, t0, t1, POLYGON_WALL_PUSH_U, z0, z1)
        if top is not None:
            tris += _face(edges, e, t0, t1, POLYGON_WALL_PUSH_U, (z0, z1), (z0 + top, z1 + top))
            _note_ends(edges, e, t0, t1, top, walls)
        return tris
    gap, other = found
    rise = other - zm
    if abs(rise) <= JUMP_U and gap <= BRIDGE_MAX_GAP_U:
        # past the edge's ends too, square: where several areas' corners meet, the hole
        # between them is closed (each strip alone leaves the corner open)
        c0 = t0 - gap / 2 if t0 <= TOUCH_TOL_U else t0
        c1 = t1 + gap / 2 if t1 >= edges.length[e] - TOUCH_TOL_U else t1
        tris = _strip(edges, e, c0, c1, gap / 2, *(float(edges.point(e, t)[2]) for t in (c0, c1)))
        if rise < -STEP_U:  # the higher side closes the step
            tris += _face(edges, e, t0, t1, gap / 2, (z0, z1), (other, other))
        return tris
    push = min(POLYGON_WALL_PUSH_U, gap / 2)
    tris = _strip(edges, e, t0, t1, push, z0, z1)
    # under a walkway the lower floor goes on beneath the upper one: no face there
    x, y, _ = edges.point(e, mid, -PROBES_U[1] if rise < 0 else gap + PROBES_U[1])
    if abs(rise) > OVERHEAD_U and _floor_near(floors, x, y, min(zm, other), edges.area[e]):
        return tris
    return tris + _face(edges, e, t0, t1, push, (z0, z1), (other, other))


def _wall_top(edges: Edges, floors: Floors, e: int, t: float, z: float) -> float | None:
    """A wall's height above its foot at `t` of edge e: `WALL_HEIGHT_U`, capped below a floor
    overhead; None where the wall would stand on another floor of about the same level."""
    x, y, _ = edges.point(e, t, POLYGON_WALL_PUSH_U)
    top = WALL_HEIGHT_U
    for area, h in floors.under(x, y):
        if area == edges.area[e]:
            continue
        if abs(h - z) <= JUMP_U:
            return None
        if h - z > OVERHEAD_U:
            top = min(top, h - z - 8)
    return top


def _note_ends(
    edges: Edges,
    e: int,
    t0: float,
    t1: float,
    top: float,
    walls: CornerNotes,
) -> None:
    """Note a wall piece's ends that sit at a corner of its edge, keyed by the corner."""
    for t, kind in ((t0, "starts"), (t1, "ends")):
        at_corner = t <= TOUCH_TOL_U or t >= edges.length[e] - TOUCH_TOL_U
        if at_corner:
            corner = edges.point(e, 0.0 if kind == "starts" else edges.length[e])
            key = (round(float(corner[0]), 0), round(float(corner[1]), 0))
            walls[key].append((kind, edges.point(e, t, POLYGON_WALL_PUSH_U), float(corner[2]), top))


def _corner_walls(
    walls: CornerNotes,
) -> list:
    """A wall from each wall that ends at a corner to each that starts there (same level)."""
    tris: list = []
    for ends in walls.values():
        for kind_a, pa, za, top_a in ends:
            for kind_b, pb, zb, top_b in ends:
                if kind_a != "ends" or kind_b != "starts" or abs(za - zb) > JUMP_U:
                    continue
                if np.hypot(*(pa - pb)[:2]) <= 0.5:
                    continue
                top = min(top_a, top_b)
                tris += quad(
                    (pa[0], pa[1], za), (pb[0], pb[1], zb), (pb[0], pb[1], zb + top),
                    (pa[0], pa[1], za + top),
                )  # fmt: skip
    return tris


def _strip(edges: Edges, e: int, t0: float, t1: float, width: float, z0: float, z1: float):
    """The area's floor carried `width` beyond edge e between t0 and t1."""
    if width <= 0.5:
        return []
    a, b = edges.point(e, t0), edges.point(e, t1)
    c, d = edges.point(e, t1, width), edges.point(e, t0, width)
    return quad((*a[:2], z0), (*b[:2], z1), (*c[:2], z1), (*d[:2], z0))


def _face(edges: Edges, e: int, t0: float, t1: float, push: float, low, high):
    """A vertical face on the line `push` beyond edge e, between two height profiles."""
    a, b = edges.point(e, t0, push), edges.point(e, t1, push)
    return quad((*a[:2], low[0]), (*b[:2], low[1]), (*b[:2], high[1]), (*a[:2], high[0]))


def open_edge_rays(
    nav: PolygonNav, heights: tuple[float, ...], reach: float, back: float = 8.0
) -> tuple[np.ndarray, np.ndarray, float]:
    """Horizontal rays out of the middle of every open piece with no floor beyond it within
    reach (a wall, and nothing else, there), one per height above its floor, from `back` inside
    the edge to `reach` beyond it: (starts, ends) in Hammer units and `back`, what a study of
    how far the real walls stand casts against a map's geometry
    (benchmarks/studies/cs2_world.py)."""
    floors, edges = Floors(nav), Edges(nav)
    covered, _ = _shared_stretches(edges, floors)
    starts, ends = [], []
    for e, t0, t1, found in _open_pieces(edges, floors, covered):
        if found is not None:
            continue
        t = (t0 + t1) / 2
        z = float(edges.point(e, t)[2])
        for height in heights:
            starts.append([*edges.point(e, t, -back)[:2], z + height])
            ends.append([*edges.point(e, t, reach)[:2], z + height])
    return np.asarray(starts).reshape(-1, 3), np.asarray(ends).reshape(-1, 3), back
