"""The triangles of a nav mesh: fitted corner heights, floors, step faces, bridges, walls pushed
out to the real walls, ledge faces and patch boxes (decoy_cli/world/navmesh.py says why each).

One algorithm kept in one module: every face is decided from the same per-side view of the
areas (what touches each side, at which height, within which reach), so the parts share it.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.sparse import coo_matrix
from scipy.sparse.linalg import lsqr

from decoy_cli.world.nav_data import NavMesh

HEIGHT_DECIMALS = 3
"""Fitted corner heights are rounded to this many decimals of a Hammer unit."""
WALL_PUSH_U = 16.0
"""How far walls stand beyond the nav edge (half a player hull)."""
BRIDGE_MAX_GAP_U = 32.0
"""Connected areas whose facing edges are at most this far apart get a bridging floor."""
TOUCH_TOL_U = 1.0
"""Edges closer than this count as touching."""
MAX_SHARED_STEP_U = 320.0
"""Touching areas further apart in height than this are not neighbours: the edge gets a wall."""
WALL_HEIGHT_U = 184.0
"""Wall height above its floor (3.5 m), capped below any floor overhead."""
SEAM_MATCH_U = 24.0
"""Touching edges whose heights differ by less than this are fitted to meet (else a ledge)."""
LEDGE_REACH_U = 128.0
"""A lower floor this far beyond an open side makes the side a ledge (a drop), not a wall."""
STEP_U = 18.0
"""The CS:GO step height."""
JUMP_U = 64.0
"""Areas closer in height than a crouch-jump count as the same floor for gaps and walls."""


# ---- corner heights ---------------------------------------------------------------------------


@dataclass(frozen=True)
class _Contact:
    """Two areas touching along an axis-aligned segment (Hammer units)."""

    a: int
    b: int
    axis: int  # 0: the shared edge is vertical (x = const), 1: horizontal (y = const)
    coord: float  # the constant coordinate of the shared edge
    lo: float  # extent of the overlap along the edge
    hi: float


def _corner_heights(nav: NavMesh, zx: np.ndarray, zy: np.ndarray):
    """The four corner heights: (x_min,y_min), (x_max,y_min), (x_min,y_max), (x_max,y_max)."""
    return nav.z_at_min, zx, zy, nav.z_at_max


def _height(nav: NavMesh, zx, zy, area: int, x: float, y: float) -> float:
    """Bilinear floor height of an area at a point of its rectangle (clamped)."""
    u = np.clip((x - nav.x_min[area]) / (nav.x_max[area] - nav.x_min[area]), 0, 1)
    v = np.clip((y - nav.y_min[area]) / (nav.y_max[area] - nav.y_min[area]), 0, 1)
    z00, z10, z01, z11 = (c[area] for c in _corner_heights(nav, zx, zy))
    return float(z00 * (1 - u) * (1 - v) + z10 * u * (1 - v) + z01 * (1 - u) * v + z11 * u * v)


def _find_contacts(nav: NavMesh) -> list[_Contact]:
    """Every pair of areas whose rectangles touch along a segment of positive length."""
    contacts = []
    for axis, (lo_a, hi_a, lo_t, hi_t) in enumerate(
        ((nav.x_min, nav.x_max, nav.y_min, nav.y_max), (nav.y_min, nav.y_max, nav.x_min, nav.x_max))
    ):
        # a's high side touches b's low side
        touch = np.abs(hi_a[:, None] - lo_a[None, :]) <= TOUCH_TOL_U
        lo = np.maximum(lo_t[:, None], lo_t[None, :])
        hi = np.minimum(hi_t[:, None], hi_t[None, :])
        touch &= hi - lo > TOUCH_TOL_U
        for a, b in zip(*np.nonzero(touch), strict=True):
            contacts.append(_Contact(int(a), int(b), axis, float(hi_a[a]), lo[a, b], hi[a, b]))
    return contacts


def _edge_point(c: _Contact, t: float) -> tuple[float, float]:
    along = c.lo + t * (c.hi - c.lo)
    return (c.coord, along) if c.axis == 0 else (along, c.coord)


def fit_corner_heights(nav: NavMesh, contacts: list[_Contact]) -> tuple[np.ndarray, np.ndarray]:
    """Least-squares heights of the two corners awpy dropped, so touching floors meet.

    Unknowns: per area the height at (x_max, y_min) and at (x_min, y_max). Equations: along every
    shared edge whose two sides are roughly level (a seam, not a ledge), both bilinear floors give
    the same height at the overlap's ends; per area, a weak pull toward a plane through the two
    known corners keeps isolated areas sensible.
    """
    n = nav.num_areas
    guess = (nav.z_at_min + nav.z_at_max) / 2
    rows, cols, vals, rhs = [], [], [], []

    def coefficients(area: int, x: float, y: float):
        u = np.clip((x - nav.x_min[area]) / (nav.x_max[area] - nav.x_min[area]), 0, 1)
        v = np.clip((y - nav.y_min[area]) / (nav.y_max[area] - nav.y_min[area]), 0, 1)
        known = nav.z_at_min[area] * (1 - u) * (1 - v) + nav.z_at_max[area] * u * v
        return u * (1 - v), (1 - u) * v, known  # weights of zx, zy, and the known part

    eq = 0
    for c in contacts:
        for t in (0.0, 1.0):
            x, y = _edge_point(c, t)
            wa_x, wa_y, ka = coefficients(c.a, x, y)
            wb_x, wb_y, kb = coefficients(c.b, x, y)
            if abs((ka + (wa_x + wa_y) * guess[c.a]) - (kb + (wb_x + wb_y) * guess[c.b])) > (
                SEAM_MATCH_U
            ):
                continue
            rows += [eq] * 4
            cols += [c.a, n + c.a, c.b, n + c.b]
            vals += [wa_x, wa_y, -wb_x, -wb_y]
            rhs.append(kb - ka)
            eq += 1
    weak = 0.05
    for a in range(n):
        rows += [eq, eq, eq + 1, eq + 1]
        cols += [a, n + a, a, n + a]
        vals += [weak, weak, weak, -weak]
        rhs += [weak * 2 * guess[a], 0.0]
        eq += 2
    matrix = coo_matrix((vals, (rows, cols)), shape=(eq, 2 * n)).tocsr()
    solution = lsqr(matrix, np.asarray(rhs), atol=1e-10, btol=1e-10, iter_lim=20000)[0]
    # The iterations' last bits depend on the CPU's BLAS kernels (differences of ~3e-8 units seen
    # between kernels); rounding far below anything that matters (a thousandth of a unit, 25 µm)
    # makes the world the same on every machine unless a height falls within that much of a
    # rounding boundary (none does for de_dust2; the graph test would show it).
    solution = np.round(solution, HEIGHT_DECIMALS)
    return solution[:n], solution[n:]


# ---- triangles --------------------------------------------------------------------------------


def quad(p0, p1, p2, p3) -> list[list[tuple[float, float, float]]]:
    """Two triangles of the quad p0-p1-p2-p3 (in order around its boundary)."""
    return [[p0, p1, p2], [p0, p2, p3]]


def subtract(interval: tuple[float, float], covers: list[tuple[float, float]]):
    """Parts of a 1-D interval not covered by any of `covers`."""
    pieces = [interval]
    for lo, hi in covers:
        nxt = []
        for a, b in pieces:
            if hi <= a or lo >= b:
                nxt.append((a, b))
                continue
            if lo > a:
                nxt.append((a, lo))
            if hi < b:
                nxt.append((hi, b))
        pieces = nxt
    return [(a, b) for a, b in pieces if b - a > TOUCH_TOL_U]


def floor_corner_heights(nav: NavMesh) -> tuple[np.ndarray, np.ndarray]:
    """The fitted heights of every area's (x_max, y_min) and (x_min, y_max) corners, Hammer units:
    with the two known corners they give the bilinear floor the world is built from."""
    return fit_corner_heights(nav, _find_contacts(nav))


def build_nav_triangles(nav: NavMesh) -> np.ndarray:
    """Floors, step faces, bridges and walls of the nav world, (T, 3, 3) in Hammer units."""
    contacts = _find_contacts(nav)
    zx, zy = fit_corner_heights(nav, contacts)
    height = lambda area, x, y: _height(nav, zx, zy, area, x, y)  # noqa: E731
    tris, covered = _floors_and_joins(nav, contacts, height)
    tris += _walls(nav, covered, height)
    return np.asarray(tris, dtype=np.float64)


def open_stretches(nav: NavMesh) -> list[tuple[_Side, _OpenPart]]:
    """Every open stretch of an area side (touching no area) with its side and the nearest area
    beyond it (`other` -1: none near, a full wall): what a study of the walls and ledges
    (benchmarks/studies/ledge_candidates.py) looks at."""
    contacts = _find_contacts(nav)
    zx, zy = fit_corner_heights(nav, contacts)
    height = lambda area, x, y: _height(nav, zx, zy, area, x, y)  # noqa: E731
    return _open_stretches(nav, _floors_and_joins(nav, contacts, height)[1])


def _floors_and_joins(nav: NavMesh, contacts: list[_Contact], height) -> tuple[list, dict]:
    """Floors, step faces and bridges, and the stretches of each side (area, axis * 2 + high)
    they cover: the rest of every side is open (`_walls`)."""
    tris: list = []

    # floors
    for a in range(nav.num_areas):
        x0, x1, y0, y1 = nav.x_min[a], nav.x_max[a], nav.y_min[a], nav.y_max[a]
        tris += quad(
            (x0, y0, height(a, x0, y0)),
            (x1, y0, height(a, x1, y0)),
            (x1, y1, height(a, x1, y1)),
            (x0, y1, height(a, x0, y1)),
        )

    # each area side: the outward normal, its constant coordinate and its extent
    covered: dict[tuple[int, int], list[tuple[float, float]]] = {}

    def side_key(area: int, axis: int, high: bool) -> tuple[int, int]:
        return area, axis * 2 + int(high)

    def point_on(c: _Contact, along: float) -> tuple[float, float]:
        return (c.coord, along) if c.axis == 0 else (along, c.coord)

    def step_face(c: _Contact, lo: float, hi: float) -> None:
        p0, p1 = point_on(c, lo), point_on(c, hi)
        za0, za1 = height(c.a, *p0), height(c.a, *p1)
        zb0, zb1 = height(c.b, *p0), height(c.b, *p1)
        if max(abs(za0 - zb0), abs(za1 - zb1)) > 1.0:
            tris.extend(quad((*p0, za0), (*p1, za1), (*p1, zb1), (*p0, zb0)))

    rise = {}
    level: dict[tuple[int, int], list[tuple[float, float]]] = {}
    for c in contacts:
        rise[c] = height(c.b, *_edge_point(c, 0.5)) - height(c.a, *_edge_point(c, 0.5))
        if abs(rise[c]) <= SEAM_MATCH_U:
            level.setdefault(side_key(c.a, c.axis, True), []).append((c.lo, c.hi))
            level.setdefault(side_key(c.b, c.axis, False), []).append((c.lo, c.hi))
    for c in contacts:
        if abs(rise[c]) > MAX_SHARED_STEP_U:
            continue
        covered.setdefault(side_key(c.a, c.axis, True), []).append((c.lo, c.hi))
        covered.setdefault(side_key(c.b, c.axis, False), []).append((c.lo, c.hi))
        if abs(rise[c]) <= 72:
            step_face(c, c.lo, c.hi)
            continue
        # A high ledge: where the lower floor goes on under the upper one, there is no face.
        lower_side = side_key(c.a, c.axis, True) if rise[c] > 0 else side_key(c.b, c.axis, False)
        for lo, hi in subtract((c.lo, c.hi), level.get(lower_side, [])):
            step_face(c, lo, hi)

    # bridges across small gaps between connected areas
    linked = {(int(a), int(b)) for a, b in nav.connections}
    linked |= {(b, a) for a, b in linked}
    for a, b in sorted(linked):
        if a > b:
            continue
        for axis in (0, 1):
            lo_a, hi_a = (nav.x_min, nav.x_max) if axis == 0 else (nav.y_min, nav.y_max)
            lo_t, hi_t = (nav.y_min, nav.y_max) if axis == 0 else (nav.x_min, nav.x_max)
            for first, second in ((a, b), (b, a)):
                gap = lo_a[second] - hi_a[first]
                lo, hi = max(lo_t[first], lo_t[second]), min(hi_t[first], hi_t[second])
                if not (TOUCH_TOL_U < gap <= BRIDGE_MAX_GAP_U and hi - lo > TOUCH_TOL_U):
                    continue
                c0, mid, c1 = hi_a[first], hi_a[first] + gap / 2, lo_a[second]

                def point(along: float, across: float) -> tuple[float, float]:
                    return (across, along) if axis == 0 else (along, across)  # noqa: B023

                for area, near, far in ((first, c0, mid), (second, c1, mid)):
                    z_lo = height(area, *point(lo, near))
                    z_hi = height(area, *point(hi, near))
                    tris += quad(
                        (*point(lo, near), z_lo),
                        (*point(hi, near), z_hi),
                        (*point(hi, far), z_hi),
                        (*point(lo, far), z_lo),
                    )
                z_first = [height(first, *point(s, c0)) for s in (lo, hi)]
                z_second = [height(second, *point(s, c1)) for s in (lo, hi)]
                tris += quad(
                    (*point(lo, mid), z_first[0]),
                    (*point(hi, mid), z_first[1]),
                    (*point(hi, mid), z_second[1]),
                    (*point(lo, mid), z_second[0]),
                )
                covered.setdefault(side_key(first, axis, True), []).append((lo, hi))
                covered.setdefault(side_key(second, axis, False), []).append((lo, hi))
    return tris, covered


def _open_stretches(nav: NavMesh, covered) -> list[tuple[_Side, _OpenPart]]:
    """The open parts of every area side (parts that touch no area), with what lies beyond them
    (see `_Side.open_parts`)."""
    stretches = []
    for a in range(nav.num_areas):
        for axis in (0, 1):
            for high in (False, True):
                side = _Side(nav, a, axis, high, covered)
                for lo, hi in subtract((side.lo, side.hi), covered.get((a, axis * 2 + high), [])):
                    stretches += [(side, part) for part in side.open_parts(lo, hi)]
    return stretches


def _walls(nav: NavMesh, covered, height) -> list:
    """Faces along the open parts of every area side, by what lies beyond them."""
    return [tri for side, part in _open_stretches(nav, covered) for tri in side.faces(part, height)]


@dataclass(frozen=True)
class _OpenPart:
    """A stretch [lo, hi] of an open side and the nearest area beyond it (-1: none near)."""

    lo: float
    hi: float
    other: int
    gap: float


class _Side:
    """One side of a nav area: its line, its outward direction and the areas beyond it."""

    def __init__(self, nav: NavMesh, area: int, axis: int, high: bool, covered) -> None:
        self.nav, self.area, self.axis = nav, area, axis
        self.covered = covered
        self.sign = 1.0 if high else -1.0
        if axis == 0:  # the side is the line x = coord, running along y
            self.lo, self.hi = nav.y_min[area], nav.y_max[area]
            self.coord = nav.x_max[area] if high else nav.x_min[area]
            self.near_lo, self.near_hi = nav.x_min, nav.x_max
            self.t_lo, self.t_hi = nav.y_min, nav.y_max
        else:  # the line y = coord, running along x
            self.lo, self.hi = nav.x_min[area], nav.x_max[area]
            self.coord = nav.y_max[area] if high else nav.y_min[area]
            self.near_lo, self.near_hi = nav.y_min, nav.y_max
            self.t_lo, self.t_hi = nav.x_min, nav.x_max
        self.centre_z = (nav.z_at_min + nav.z_at_max) / 2
        self.gap = (self.near_lo - self.coord) if high else (self.coord - self.near_hi)

    def point(self, along: float, across: float) -> tuple[float, float]:
        return (across, along) if self.axis == 0 else (along, across)

    def open_parts(self, lo: float, hi: float) -> list[_OpenPart]:
        """Split [lo, hi] by the nearest area facing each stretch within 3 push widths."""
        overlap = (np.minimum(self.t_hi, hi) - np.maximum(self.t_lo, lo)) > TOUCH_TOL_U
        dz = np.abs(self.centre_z - self.centre_z[self.area])
        other_level = np.abs(self.centre_z - self.centre_z[self.area]) > JUMP_U
        near = overlap & (self.gap >= -TOUCH_TOL_U)
        near &= (self.gap <= 3 * WALL_PUSH_U) | (other_level & (self.gap <= LEDGE_REACH_U))
        near &= dz <= MAX_SHARED_STEP_U
        near[self.area] = False
        parts, rest = [], [(lo, hi)]
        for b in sorted(np.nonzero(near)[0], key=lambda b: (self.gap[b], b)):
            span = (max(lo, self.t_lo[b]), min(hi, self.t_hi[b]))
            for p_lo, p_hi in rest:
                c_lo, c_hi = max(p_lo, span[0]), min(p_hi, span[1])
                if c_hi - c_lo > TOUCH_TOL_U:
                    parts.append(_OpenPart(c_lo, c_hi, int(b), max(0.0, float(self.gap[b]))))
            rest = [q for p in rest for q in subtract(p, [span])]
        parts += [_OpenPart(p_lo, p_hi, -1, np.inf) for p_lo, p_hi in rest]
        return sorted(parts, key=lambda q: q.lo)

    def faces(self, part: _OpenPart, height) -> list:
        """Triangles for one open stretch, by what lies beyond it:

        * nothing near: a wall pushed out by 16 u, full height (capped below floors overhead);
        * an area at about the same height across a small gap: floor to the middle of the gap
          (a hole in the mesh, not a wall), with a step face there if the heights differ;
        * a lower area: a ledge; the floor runs to the pushed line, then a face goes down;
        * a higher area: the foot of a box or ledge; a face goes up to the other's height.
        In every case the floor is extended under the push.
        """
        z0 = height(self.area, *self.point(part.lo, self.coord))
        z1 = height(self.area, *self.point(part.hi, self.coord))
        if part.other < 0:
            push = WALL_PUSH_U
            return self._strip(part, push, z0, z1) + self._wall(part, push, z0, z1)
        o0 = height(part.other, *self.point(part.lo, self.coord + self.sign * part.gap))
        o1 = height(part.other, *self.point(part.hi, self.coord + self.sign * part.gap))
        rise = (o0 + o1) / 2 - (z0 + z1) / 2
        if abs(rise) <= JUMP_U and part.gap <= BRIDGE_MAX_GAP_U:
            push = part.gap / 2
            tris = self._strip(part, push, z0, z1)
            if rise < -STEP_U:  # the higher side closes the step
                tris += self._vertical(part, push, (z0, z1), (o0, o1))
            return tris
        push = min(WALL_PUSH_U, part.gap / 2)
        tris = self._strip(part, push, z0, z1)
        # Where the lower floor goes on under the upper one across the face's line (a walkway
        # over a passage, not a box), there is no face.
        out = self.coord + self.sign * push
        lower = min((z0 + z1) / 2, (o0 + o1) / 2)
        for p_lo, p_hi in self._outside_areas(part.lo, part.hi, out, lower):
            piece = _OpenPart(p_lo, p_hi, part.other, part.gap)
            za = tuple(height(self.area, *self.point(v, self.coord)) for v in (p_lo, p_hi))
            zb = tuple(
                height(part.other, *self.point(v, self.coord + self.sign * part.gap))
                for v in (p_lo, p_hi)
            )
            tris += self._vertical(piece, push, za, zb)
        return tris

    def _outside_areas(
        self, lo: float, hi: float, out: float, level_z: float, clearance: float = 0.0
    ) -> list:
        """The parts of [lo, hi] on the line at `out` that stand inside no other area whose
        floor is within a jump of `level_z`, nor within `clearance` of its ends along the line."""
        across = (self.near_lo + TOUCH_TOL_U < out) & (out < self.near_hi - TOUCH_TOL_U)
        along = (self.t_hi + clearance > lo) & (self.t_lo - clearance < hi)
        inside = across & along & (np.abs(self.centre_z - level_z) <= JUMP_U)
        inside[self.area] = False
        spans = zip(self.t_lo[inside] - clearance, self.t_hi[inside] + clearance, strict=True)
        return subtract((lo, hi), list(spans))

    def _strip(self, part: _OpenPart, width: float, z0: float, z1: float) -> list:
        """The area's floor extended outward by `width`."""
        if width <= 0.5:
            return []
        out = self.coord + self.sign * width
        return quad(
            (*self.point(part.lo, self.coord), z0),
            (*self.point(part.hi, self.coord), z1),
            (*self.point(part.hi, out), z1),
            (*self.point(part.lo, out), z0),
        )

    def _vertical(self, part: _OpenPart, push: float, za, zb) -> list:
        """A vertical face on the pushed line between two height profiles."""
        out = self.coord + self.sign * push
        return quad(
            (*self.point(part.lo, out), za[0]),
            (*self.point(part.hi, out), za[1]),
            (*self.point(part.hi, out), zb[1]),
            (*self.point(part.lo, out), zb[0]),
        )

    def _open_corner(self, end: float, high_end: bool) -> bool:
        """True at a corner of the area whose other side is open there too (a convex corner
        walled on both sides): only there does a wall grow past its end to close the corner.
        Growing elsewhere would stick into the passage next to the corner."""
        corner = self.hi if high_end else self.lo
        if abs(end - corner) > TOUCH_TOL_U:
            return False
        other_key = (self.area, (1 - self.axis) * 2 + int(high_end))
        return not any(
            lo - TOUCH_TOL_U <= self.coord <= hi + TOUCH_TOL_U
            for lo, hi in self.covered.get(other_key, [])
        )

    def _wall(self, part: _OpenPart, push: float, z0: float, z1: float) -> list:
        """A full wall on the pushed line, grown at the area's corners, cut where it would stand
        inside another area of about the same height, and capped below any floor overhead."""
        nav = self.nav
        out = self.coord + self.sign * push
        a0 = part.lo - (push if self._open_corner(part.lo, high_end=False) else 0.0)
        a1 = part.hi + (push if self._open_corner(part.hi, high_end=True) else 0.0)
        # A wall stands as far from another floor's end as from its own area (`push`): the nav
        # stops that far short of the real walls on every side, doorways included.
        pieces = self._outside_areas(a0, a1, out, (z0 + z1) / 2, clearance=push)
        across = (self.near_lo + TOUCH_TOL_U < out) & (out < self.near_hi - TOUCH_TOL_U)
        along = (self.t_hi > a0) & (self.t_lo < a1)
        clearance = np.minimum(nav.z_at_min, nav.z_at_max) - max(z0, z1)
        overhead = across & along & (clearance > 72)
        top = WALL_HEIGHT_U
        if overhead.any():
            top = min(top, float(clearance[overhead].min()) - 8)
        return [
            tri
            for p_lo, p_hi in pieces
            for tri in quad(
                (*self.point(p_lo, out), z0),
                (*self.point(p_hi, out), z1),
                (*self.point(p_hi, out), z1 + top),
                (*self.point(p_lo, out), z0 + top),
            )
        ]


def box_triangles(x_min, y_min, x_max, y_max, z_top, z_bottom) -> np.ndarray:
    """A closed box's top and four sides, (10, 3, 3) (the bottom is never seen)."""
    top = [
        (x_min, y_min, z_top),
        (x_max, y_min, z_top),
        (x_max, y_max, z_top),
        (x_min, y_max, z_top),
    ]
    low = [(x, y, z_bottom) for x, y, _ in top]
    tris = [[top[0], top[1], top[2]], [top[0], top[2], top[3]]]
    for i in range(4):
        j = (i + 1) % 4
        tris += [[low[i], low[j], top[j]], [low[i], top[j], top[i]]]
    return np.array(tris, dtype=np.float64)
