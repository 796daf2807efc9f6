"""Build the waypoint graph of a world: the paper's three stages, then pruning and manual points.

1. **Lattice (BFS).** From seed points, a breadth-first flood over a square lattice (0.7 m) in the
   8 compass directions. A move to a neighbour is tested with rays in the physics world: a ray
   down finds the neighbour's floor; rays down along the edge sample the floor profile (so a ramp,
   whose height change over a 0.99 m diagonal can exceed the step height, is told from a ledge);
   a ray up checks headroom; nine rays at the capsule's centre line and edges, at knee, waist and
   head height, check the body's way. Moves become walk, step (ledge up to 18 u) or jump (up to a
   crouch-jump) edges, in both directions where both pass.
2. **Drop pass.** Moves whose profile falls by more than the step height (down to the safe-fall
   depth) become one-way drop edges; lower floors first found this way are flooded too.
   **Wall nodes** (the project's addition, `wall_nodes`): where a node has no level move in a
   cardinal direction (a wall, a railing, a cliff edge, the face of a box it jumps onto), a node
   is added toward it, as close as the capsule allows, if the floor continues on the same level
   and the capsule fits there, linked to its parent both ways and to the wall nodes of its
   lattice neighbours along the wall; a jump or drop the parent had that way now leaves from the
   wall node. Players hug walls and wait at box faces: on the pure lattice such a position can
   be up to 0.7 m from every node. Measured on the built-in world (`decoy build-waypoints
   --check-esta`, all 250,320 real T positions): 6.6% are more than 0.5 m away horizontally
   without wall nodes, 5.5% with them; 3-D on the ground, 95.80% -> 96.99% within 0.5 m.
   Each node still has at most one edge per direction.
3. **Verification.** A capsule is moved along every edge in pybullet, in steps of at most
   0.1 m, floating the step height above the floor (as the simulator moves agents); an edge
   along which it would penetrate the world is removed. First (before wall nodes are placed,
   so that they stand against the final positions), a node where the capsule does not fit (a
   lattice point that happens to lie too close to a wall) is moved up to 0.3 m to where it
   fits, instead of being lost: without that, a quarter of the lattice's edges near walls die.
   The capsule is 20% thinner than the CS:GO hull (radius 12.8 u, not 16 u): the nav world's
   walls stand up to 16 u beyond the nav edge, often less where areas face each other across
   narrow gaps, and the thinner capsule tolerates that approximation (measured: with the full
   radius 96.4% of the nodes are in the largest strongly connected component, with 12.8 u 98.6%).

Then the graph is pruned to its largest strongly connected component (so an agent can always get
back), manual waypoints are merged in, each node gets its nav place, and nodes are numbered in a
fixed order so the same inputs give the same file.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import asdict, dataclass, field

import numpy as np
from scipy.sparse import csr_matrix
from scipy.sparse.csgraph import connected_components

from decoy_cli.csgo import (
    JUMP_HEIGHT_M,
    MAX_DROP_M,
    PLAYER_HEIGHT_M,
    PLAYER_RADIUS_M,
    STEP_HEIGHT_M,
)
from decoy_cli.errors import GraphError
from decoy_cli.waypoints.graph import DIRECTION_VECTORS, EdgeKind
from decoy_cli.world.physics import PhysicsWorld

BLOCKED = -1
Progress = Callable[[str, int, int], None]
"""progress(stage, done, total): called as work advances; the CLI turns it into a bar."""


@dataclass(frozen=True)
class LatticeParams:
    """Everything that shapes the lattice; stored in the graph file's metadata."""

    spacing: float = 0.7
    step_height: float = STEP_HEIGHT_M
    jump_height: float = JUMP_HEIGHT_M
    max_drop: float = MAX_DROP_M
    agent_radius: float = 0.8 * PLAYER_RADIUS_M  # see the module docstring
    agent_height: float = PLAYER_HEIGHT_M
    min_floor_normal_z: float = 0.7  # CS:GO: surfaces steeper than ~45 degrees are not floors
    profile_samples: int = 8
    ledge_threshold: float = 0.12  # a profile jump above this is a ledge, below it a ramp
    same_floor_dz: float = 0.6  # two lattice hits closer than this in height are one node
    verify_step: float = 0.1
    verify_clearance: float = 0.03  # capsule floats this much above the step height
    max_nudge: float = 0.3  # a node the capsule does not fit at moves up to this far to fit
    graze: float = 0.025  # penetration the capsule may have (the walls are approximate)
    wall_nodes: bool = True  # add nodes half a spacing toward walls (see the module docstring)


@dataclass
class BuildStats:
    """What the build did, stage by stage (the CLI prints it, the graph file stores it)."""

    seeds: int = 0
    lattice_nodes: int = 0
    lattice_edges: dict[str, int] = field(default_factory=dict)
    drop_edges: int = 0
    drop_new_nodes: int = 0
    wall_nodes: int = 0
    nudged_nodes: int = 0
    verified_removed: dict[str, int] = field(default_factory=dict)
    components_before: int = 0
    largest_component_share: float = 0.0
    components_after: int = 0
    pruned_nodes: int = 0
    manual_added: int = 0
    manual_dropped: int = 0
    nodes: int = 0
    edges: dict[str, int] = field(default_factory=dict)
    seconds: dict[str, float] = field(default_factory=dict)

    def as_dict(self) -> dict:
        return asdict(self)


@dataclass
class LatticeResult:
    """Nodes and edges after all stages, plus what was removed (for plots and reports)."""

    positions: np.ndarray
    edge_source: np.ndarray
    edge_target: np.ndarray
    edge_kind: np.ndarray
    edge_direction: np.ndarray
    removed_segments: np.ndarray  # (R, 2, 3) start and end of edges removed by verification
    removed_kinds: np.ndarray  # (R,) EdgeKind of each removed edge
    pruned_positions: np.ndarray  # (Q, 3) nodes dropped by the component pruning
    stats: BuildStats


class _Lattice:
    """Growing node set keyed by lattice cell, several floors per cell."""

    def __init__(self, origin: np.ndarray, params: LatticeParams) -> None:
        self.origin = origin[:2].copy()
        self.params = params
        self.positions: list[np.ndarray] = []
        self.cell_of: list[tuple[int, int]] = []
        self.cells: dict[tuple[int, int], list[int]] = {}

    def cell(self, xy: np.ndarray) -> tuple[int, int]:
        ij = np.rint((xy - self.origin) / self.params.spacing).astype(np.int64)
        return int(ij[0]), int(ij[1])

    def xy(self, cell: tuple[int, int]) -> np.ndarray:
        return self.origin + np.array(cell, dtype=np.float64) * self.params.spacing

    def find_or_add(self, cell: tuple[int, int], z: float) -> tuple[int, bool]:
        for node in self.cells.get(cell, []):
            if abs(self.positions[node][2] - z) < self.params.same_floor_dz:
                return node, False
        node = len(self.positions)
        self.positions.append(np.array([*self.xy(cell), z]))
        self.cell_of.append(cell)
        self.cells.setdefault(cell, []).append(node)
        return node, True


def _evaluate_moves(
    physics: PhysicsWorld,
    sources: np.ndarray,
    directions: np.ndarray,
    params: LatticeParams,
    scale: np.ndarray | None = None,
) -> tuple[np.ndarray, np.ndarray]:
    """Classify moves from source positions in compass directions: (EdgeKind or -1, target z).

    A move goes `scale` times the direction's lattice vector (default: the spacing)."""
    k = len(sources)
    if k == 0:
        return np.zeros(0, dtype=np.int64), np.zeros(0)
    scale = np.full(k, params.spacing) if scale is None else np.asarray(scale, dtype=np.float64)
    step = DIRECTION_VECTORS[directions].astype(np.float64) * scale[:, None]
    target_xy = sources[:, :2] + step
    top = params.jump_height + 0.05
    start = np.column_stack([target_xy, sources[:, 2] + top])
    target_z, normal_z = physics.first_floor_below(start, top + params.max_drop)
    kind = np.full(k, BLOCKED, dtype=np.int64)
    ok = np.isfinite(target_z) & (normal_z >= params.min_floor_normal_z)

    # floor profile along the move
    s = params.profile_samples
    t = np.arange(1, s + 1) / (s + 1)
    high = np.fmax(sources[:, 2], np.where(ok, target_z, sources[:, 2]))
    prof_xy = sources[:, None, :2] + t[None, :, None] * step[:, None, :]
    prof_start = np.concatenate(
        [prof_xy, np.broadcast_to((high + top)[:, None, None], (k, s, 1))], 2
    )
    depth = top + params.max_drop + np.abs(high - sources[:, 2])
    prof_z, _ = physics.first_floor_below(prof_start.reshape(-1, 3), float(np.max(depth)))
    prof_z = prof_z.reshape(k, s)
    ok &= np.all(np.isfinite(prof_z), axis=1)
    profile = np.column_stack([sources[:, 2], prof_z, np.where(ok, target_z, sources[:, 2])])
    d = np.diff(np.nan_to_num(profile), axis=1)
    up, down = d.max(axis=1), d.min(axis=1)
    ok &= up <= params.jump_height
    is_drop = down < -params.step_height
    ok &= ~(is_drop & (up > params.step_height))  # over a box and down: not one move

    # headroom at the target
    head = np.column_stack([target_xy, target_z + 0.05])
    head_end = head + np.array([0.0, 0.0, params.agent_height - 0.05])
    ok &= physics.line_of_sight(np.nan_to_num(head), np.nan_to_num(head_end))

    # the body's way: rays at the centre line and at both sides, three heights
    z_end = np.where(is_drop, sources[:, 2], np.where(up > params.step_height, high, target_z))
    z_start = np.where(up > params.step_height, high, sources[:, 2])
    norm = np.linalg.norm(step, axis=1, keepdims=True)
    side = np.column_stack([-step[:, 1], step[:, 0]]) / norm * params.agent_radius * 0.9
    heights = (params.step_height + 0.05, 0.5 * params.agent_height, params.agent_height - 0.05)
    starts, ends = [], []
    for h in heights:
        for offset in (0.0, 1.0, -1.0):
            starts.append(np.column_stack([sources[:, :2] + offset * side, z_start + h]))
            ends.append(np.column_stack([target_xy + offset * side, np.nan_to_num(z_end) + h]))
    # a drop also needs the fall itself free, at the target
    starts.append(np.column_stack([target_xy, sources[:, 2] + heights[0]]))
    ends.append(np.column_stack([target_xy, np.nan_to_num(target_z) + heights[0]]))
    clear = physics.line_of_sight(np.concatenate(starts), np.concatenate(ends)).reshape(-1, k)
    ok &= clear[:-1].all(axis=0) & (clear[-1] | ~is_drop)

    kind[ok & is_drop] = EdgeKind.DROP
    flat = ok & ~is_drop
    kind[flat & (up > params.step_height)] = EdgeKind.JUMP
    ledge = np.abs(d).max(axis=1) > params.ledge_threshold
    kind[flat & (up <= params.step_height) & ledge] = EdgeKind.STEP
    kind[flat & (up <= params.step_height) & ~ledge] = EdgeKind.WALK
    return kind, target_z


def _flood(
    physics: PhysicsWorld,
    lattice: _Lattice,
    frontier: list[int],
    params: LatticeParams,
    edges: list[tuple[int, int, int, int]],
    drops: list[tuple[int, int, float]],
    progress: Progress,
    stage: str,
) -> None:
    """Breadth-first expansion: walk/step/jump edges added, drop moves collected."""
    while frontier:
        frontier = sorted(frontier)
        src = np.repeat(np.asarray([lattice.positions[n] for n in frontier]), 8, axis=0)
        dirs = np.tile(np.arange(8), len(frontier))
        kinds, target_z = _evaluate_moves(physics, src, dirs, params)
        nxt = []
        for m, (kind, z) in enumerate(zip(kinds.tolist(), target_z.tolist(), strict=True)):
            u, d = frontier[m // 8], m % 8
            if kind == BLOCKED:
                continue
            if kind == EdgeKind.DROP:
                drops.append((u, d, z))
                continue
            ci, cj = lattice.cell_of[u]
            di, dj = DIRECTION_VECTORS[d]
            v, new = lattice.find_or_add((ci + int(di), cj + int(dj)), z)
            if v != u:
                edges.append((u, v, kind, d))
            if new:
                nxt.append(v)
        frontier = nxt
        progress(stage, len(lattice.positions), 0)


def _add_wall_nodes(
    physics: PhysicsWorld,
    positions: np.ndarray,
    edges: list[tuple[int, int, int, int]],
    params: LatticeParams,
) -> tuple[np.ndarray, list[tuple[int, int, int, int]]]:
    """Add a node toward every cardinal direction a node has no level move in (a wall, a
    railing, a cliff edge, the face of a box it jumps onto), as close to the wall as the capsule
    allows (half a spacing where no wall is in the way), where the floor continues level (a walk
    or step move) and the capsule fits; see the module docstring. A jump or drop the parent had
    that way now starts from the wall node, so each node keeps one edge per direction.
    Returns the positions with the new nodes appended and the new edge list."""
    n = len(positions)
    slot = {(u, d): (v, kind) for u, v, kind, d in edges}
    level_kinds = (EdgeKind.WALK, EdgeKind.STEP)
    cardinal = np.array([0, 2, 4, 6])
    free = np.array(
        [[slot.get((u, d), (0, BLOCKED))[1] not in level_kinds for d in cardinal] for u in range(n)]
    ).reshape(n, 4)
    parent, which = np.nonzero(free)
    direction = cardinal[which]
    offset = _wall_offsets(physics, positions[parent], direction, params)
    useful = offset >= _MIN_WALL_OFFSET_M
    parent, direction, offset = parent[useful], direction[useful], offset[useful]
    kinds, z = _evaluate_moves(physics, positions[parent], direction, params, offset)
    level = (kinds == EdgeKind.WALK) | (kinds == EdgeKind.STEP)
    spot = np.column_stack(
        [positions[parent, :2] + DIRECTION_VECTORS[direction] * offset[:, None], np.nan_to_num(z)]
    )
    float_h, cap_h = _capsule_dims(params)
    centres = spot + np.array([0.0, 0.0, float_h + cap_h / 2])
    fits = ~physics.capsules_blocked(centres, params.agent_radius, cap_h, params.graze)
    pairs = zip(parent.tolist(), direction.tolist(), strict=True)
    onward = np.array([slot.get(pair, (-1, BLOCKED))[0] for pair in pairs], dtype=np.int64)
    in_line = np.ones(len(parent), dtype=bool)  # an onward jump or drop stays in its direction
    has = onward >= 0
    in_line[has] = _heads_along(positions[onward[has]] - spot[has], direction[has])
    keep = np.flatnonzero(level & fits & in_line)
    wall_of: dict[tuple[int, int], int] = {}
    added: list[tuple[int, int, int, int]] = []
    for k, m in enumerate(keep.tolist()):
        u, d, w = int(parent[m]), int(direction[m]), n + k
        wall_of[(u, d)] = w
        added.append((u, w, int(kinds[m]), d))
        added.append((w, u, int(kinds[m]), (d + 4) % 8))
        if (u, d) in slot:  # the jump or drop onward now leaves from the wall node
            v, kind = slot[(u, d)]
            added.append((w, v, kind, d))
    out = [edge for edge in edges if (edge[0], edge[3]) not in wall_of] + added
    for (u, d), w in wall_of.items():
        for side in ((d + 2) % 8, (d + 6) % 8):
            neighbour = slot.get((u, side))
            if neighbour is None or neighbour[1] not in level_kinds:
                continue
            other = wall_of.get((neighbour[0], d))
            if other is not None:
                out.append((w, other, int(neighbour[1]), side))
    return np.vstack([positions, spot[keep]]), out


def _heads_along(delta: np.ndarray, directions: np.ndarray) -> np.ndarray:
    """Whether each horizontal offset points less than 45 degrees off its compass direction."""
    vectors = DIRECTION_VECTORS[directions].astype(np.float64)
    along = np.einsum("ij,ij->i", delta[:, :2], vectors / np.linalg.norm(vectors, axis=1)[:, None])
    return along > np.linalg.norm(delta[:, :2], axis=1) * np.cos(np.pi / 4)


_MIN_WALL_OFFSET_M = 0.15
"""A wall node nearer its parent than this adds no coverage worth an extra node."""


def _wall_offsets(
    physics: PhysicsWorld, sources: np.ndarray, directions: np.ndarray, params: LatticeParams
) -> np.ndarray:
    """How far toward each direction a wall node can stand: up to the nearest wall (rays at
    knee, waist and head height) minus the capsule radius, else half a spacing; at most the
    spacing less `_MIN_WALL_OFFSET_M` (beyond that it would crowd the next lattice point)."""
    reach = DIRECTION_VECTORS[directions].astype(np.float64) * params.spacing
    heights = (params.step_height + 0.05, 0.5 * params.agent_height, params.agent_height - 0.05)
    starts = np.concatenate([sources + np.array([0.0, 0.0, h]) for h in heights])
    ends = starts + np.tile(np.column_stack([reach, np.zeros(len(sources))]), (len(heights), 1))
    fraction, _ = physics.ray_test(starts, ends)
    wall = fraction.reshape(len(heights), -1).min(axis=0) * params.spacing
    offset = np.where(np.isfinite(wall), wall - params.agent_radius - 0.03, params.spacing / 2)
    return np.minimum(offset, params.spacing - _MIN_WALL_OFFSET_M)


def _capsule_dims(params: LatticeParams) -> tuple[float, float]:
    """(height above the floor of the capsule's bottom, capsule height)."""
    float_h = params.step_height + params.verify_clearance
    return float_h, params.agent_height - float_h


def _nudge_nodes(
    physics: PhysicsWorld, positions: np.ndarray, params: LatticeParams
) -> tuple[np.ndarray, int]:
    """Move nodes where the capsule does not fit (too close to a wall or ledge face) to the
    nearest spot within `max_nudge` where it does, on the same floor; returns the new positions
    and how many moved. Nodes with no such spot stay, and verification removes their edges."""
    float_h, cap_h = _capsule_dims(params)
    lift = np.array([0.0, 0.0, float_h + cap_h / 2])
    blocked = np.nonzero(
        physics.capsules_blocked(positions + lift, params.agent_radius, cap_h, params.graze)
    )[0]
    if len(blocked) == 0:
        return positions, 0
    angles = np.arange(16) * (np.pi / 8)
    rings = np.arange(1, int(np.ceil(params.max_nudge / 0.05)) + 1) * 0.05
    offsets = np.array([(r * np.cos(a), r * np.sin(a)) for r in rings for a in angles])
    moved = positions.copy()
    count = 0
    for node in blocked:
        xy = positions[node, :2] + offsets
        top = np.column_stack([xy, np.full(len(xy), positions[node, 2] + params.step_height)])
        z, nz = physics.first_floor_below(top, 2 * params.step_height)
        ok = np.isfinite(z) & (nz >= params.min_floor_normal_z)
        if not ok.any():
            continue
        cand = np.column_stack([xy[ok], z[ok]])
        free = ~physics.capsules_blocked(cand + lift, params.agent_radius, cap_h, params.graze)
        if free.any():
            moved[node] = cand[np.argmax(free)]  # offsets are ordered nearest first
            count += 1
    return moved, count


def _verify(
    physics: PhysicsWorld,
    positions: np.ndarray,
    edges: np.ndarray,
    params: LatticeParams,
    progress: Progress,
) -> np.ndarray:
    """Move a capsule along every edge; True for the edges along which it stays clear."""
    src, dst, kind = positions[edges[:, 0]], positions[edges[:, 1]], edges[:, 2]
    length = np.linalg.norm(dst[:, :2] - src[:, :2], axis=1)
    n_steps = np.maximum(1, np.ceil(length / params.verify_step)).astype(np.int64)
    float_h, cap_height = _capsule_dims(params)
    centres, owner = [], []
    for e in range(len(edges)):
        t = np.linspace(0.0, 1.0, n_steps[e] + 1)
        xy = src[e, :2] + t[:, None] * (dst[e, :2] - src[e, :2])
        if kind[e] == EdgeKind.JUMP:
            base = np.full_like(t, max(src[e, 2], dst[e, 2]))
        elif kind[e] == EdgeKind.DROP:
            base = np.full_like(t, src[e, 2])
            fall = np.linspace(src[e, 2], dst[e, 2], 4)[1:]
            xy = np.vstack([xy, np.repeat(dst[e : e + 1, :2], len(fall), axis=0)])
            base = np.concatenate([base, fall])
        else:
            base = src[e, 2] + t * (dst[e, 2] - src[e, 2])
        centres.append(np.column_stack([xy, base + float_h + cap_height / 2]))
        owner.append(np.full(len(base), e))
    all_centres = np.concatenate(centres)
    all_owner = np.concatenate(owner)
    blocked = np.zeros(len(all_centres), dtype=bool)
    chunk = 16384
    for lo in range(0, len(all_centres), chunk):
        blocked[lo : lo + chunk] = physics.capsules_blocked(
            all_centres[lo : lo + chunk], params.agent_radius, cap_height, params.graze
        )
        progress("verification", min(lo + chunk, len(all_centres)), len(all_centres))
    bad = np.zeros(len(edges), dtype=bool)
    np.logical_or.at(bad, all_owner, blocked)
    return ~bad


def _kind_counts(kinds: np.ndarray) -> dict[str, int]:
    return {k.name.lower(): int(np.sum(kinds == k)) for k in EdgeKind}


def build_lattice(
    physics: PhysicsWorld,
    seeds: np.ndarray,
    params: LatticeParams = LatticeParams(),
    manual: np.ndarray | None = None,
    progress: Progress = lambda stage, done, total: None,
) -> LatticeResult:
    """Run the three stages, prune, merge manual waypoints; see the module docstring."""
    stats = BuildStats()
    seeds = np.asarray(seeds, dtype=np.float64).reshape(-1, 3)
    if len(seeds) == 0:
        raise GraphError("no seed points: give at least one position on a floor")
    lattice = _Lattice(seeds[0], params)

    # stage 1: lattice flood from the seeds
    clock = time.perf_counter()
    frontier = []
    for k, seed in enumerate(seeds):
        cell = lattice.cell(seed[:2])
        probe = np.array([[*lattice.xy(cell), seed[2] + params.jump_height]])
        z, nz = physics.first_floor_below(probe, params.jump_height + params.max_drop)
        if not np.isfinite(z[0]) or nz[0] < params.min_floor_normal_z:
            raise GraphError(f"seed {k} at {np.round(seed, 2).tolist()} m is not above a floor")
        node, new = lattice.find_or_add(cell, float(z[0]))
        if new:
            frontier.append(node)
    stats.seeds = len(seeds)
    edges: list[tuple[int, int, int, int]] = []
    drops: list[tuple[int, int, float]] = []
    _flood(physics, lattice, frontier, params, edges, drops, progress, "lattice")
    stats.lattice_nodes = len(lattice.positions)
    stats.lattice_edges = _kind_counts(np.array([e[2] for e in edges]))
    stats.seconds["lattice"] = time.perf_counter() - clock

    # stage 2: drop edges to lower floors, flooding lower floors first found this way
    clock = time.perf_counter()
    done = 0
    while done < len(drops):
        pending, done = drops[done:], len(drops)
        new_nodes = []
        for u, d, drop_z in pending:
            ci, cj = lattice.cell_of[u]
            di, dj = DIRECTION_VECTORS[d]
            v, new = lattice.find_or_add((ci + int(di), cj + int(dj)), drop_z)
            edges.append((u, v, int(EdgeKind.DROP), d))
            stats.drop_edges += 1
            if new:
                new_nodes.append(v)
        stats.drop_new_nodes += len(new_nodes)
        _flood(physics, lattice, new_nodes, params, edges, drops, progress, "drop pass")
    stats.seconds["drop pass"] = time.perf_counter() - clock

    # stage 3: verification with a moving capsule; its nudges come first (module docstring)
    clock = time.perf_counter()
    positions, stats.nudged_nodes = _nudge_nodes(physics, np.asarray(lattice.positions), params)
    nudge_seconds = time.perf_counter() - clock
    if params.wall_nodes:
        clock = time.perf_counter()
        positions, edges = _add_wall_nodes(physics, positions, edges, params)
        stats.wall_nodes = len(positions) - len(lattice.positions)
        stats.seconds["wall nodes"] = time.perf_counter() - clock
    clock = time.perf_counter()
    edge_arr = np.asarray(edges, dtype=np.int64).reshape(-1, 4)
    keep = _verify(physics, positions, edge_arr, params, progress)
    removed = edge_arr[~keep]
    removed_segments = np.stack([positions[removed[:, 0]], positions[removed[:, 1]]], axis=1)
    stats.verified_removed = _kind_counts(removed[:, 2])
    edge_arr = edge_arr[keep]
    stats.seconds["verification"] = nudge_seconds + time.perf_counter() - clock

    # manual waypoints, then the largest strongly connected component
    clock = time.perf_counter()
    if manual is not None and len(manual):
        positions, edge_arr = _merge_manual(physics, positions, edge_arr, manual, params, stats)
    positions, edge_arr, pruned = _prune(positions, edge_arr, stats)
    positions, edge_arr = _canonical_order(positions, edge_arr)
    stats.seconds["pruning"] = time.perf_counter() - clock
    stats.nodes = len(positions)
    stats.edges = _kind_counts(edge_arr[:, 2])
    return LatticeResult(
        positions=positions,
        edge_source=edge_arr[:, 0].astype(np.int32),
        edge_target=edge_arr[:, 1].astype(np.int32),
        edge_kind=edge_arr[:, 2].astype(np.uint8),
        edge_direction=edge_arr[:, 3].astype(np.uint8),
        removed_segments=removed_segments,
        removed_kinds=removed[:, 2].astype(np.uint8),
        pruned_positions=pruned,
        stats=stats,
    )


def _prune(positions: np.ndarray, edges: np.ndarray, stats: BuildStats):
    """Keep the largest strongly connected component; return the dropped node positions too."""
    n = len(positions)
    matrix = csr_matrix((np.ones(len(edges)), (edges[:, 0], edges[:, 1])), shape=(n, n))
    count, labels = connected_components(matrix, directed=True, connection="strong")
    sizes = np.bincount(labels, minlength=count)
    largest = int(np.argmax(sizes))
    keep = labels == largest
    stats.components_before = int(count)
    stats.largest_component_share = float(sizes[largest] / n)
    stats.pruned_nodes = int(n - keep.sum())
    stats.components_after = 1
    new_index = np.full(n, -1, dtype=np.int64)
    new_index[keep] = np.arange(int(keep.sum()))
    e_keep = keep[edges[:, 0]] & keep[edges[:, 1]]
    kept_edges = edges[e_keep].copy()
    kept_edges[:, 0] = new_index[kept_edges[:, 0]]
    kept_edges[:, 1] = new_index[kept_edges[:, 1]]
    return positions[keep], kept_edges, positions[~keep]


def _canonical_order(positions: np.ndarray, edges: np.ndarray):
    """Number nodes by (x, y, z) and sort edges, so the file does not depend on BFS order."""
    rounded = np.round(positions, 6)
    order = np.lexsort((rounded[:, 2], rounded[:, 1], rounded[:, 0]))
    new_index = np.empty(len(order), dtype=np.int64)
    new_index[order] = np.arange(len(order))
    out = edges.copy()
    out[:, 0] = new_index[edges[:, 0]]
    out[:, 1] = new_index[edges[:, 1]]
    out = out[np.lexsort((out[:, 3], out[:, 0]))]
    return positions[order], out


def _merge_manual(
    physics: PhysicsWorld,
    positions: np.ndarray,
    edges: np.ndarray,
    manual: np.ndarray,
    params: LatticeParams,
    stats: BuildStats,
):
    """Add manual waypoints, linked to the nearest node in each compass sector around them.

    Each manual point is dropped onto the floor below it (it must be within 0.5 m above or below
    a floor). Links are tested like lattice moves (rays, then a moving capsule). A lattice node's
    link in the same direction is redirected to the manual point when the manual point is
    nearer, so a node keeps at most one edge per direction (the action space needs that).
    """
    positions = positions.copy()
    edge_list = [tuple(e) for e in edges.tolist()]
    for k, point in enumerate(np.asarray(manual, dtype=np.float64).reshape(-1, 3)):
        z, nz = physics.first_floor_below(point[None, :] + [0, 0, 0.5], 1.0)
        if not np.isfinite(z[0]) or nz[0] < params.min_floor_normal_z:
            raise GraphError(
                f"manual waypoint {k} at {np.round(point, 2).tolist()} m is not on a floor "
                "of the world (none within 0.5 m above or below)"
            )
        here = np.array([point[0], point[1], z[0]])
        m = len(positions)
        links = []
        delta = positions - here
        reach = 1.5 * params.spacing * np.sqrt(2)
        near = np.nonzero(
            (np.linalg.norm(delta[:, :2], axis=1) <= reach)
            & (np.abs(delta[:, 2]) <= params.jump_height)
        )[0]
        if len(near):
            angle = np.degrees(np.arctan2(delta[near, 0], delta[near, 1])) % 360  # from north
            sector = np.rint(angle / 45).astype(np.int64) % 8
            for d in range(8):
                cand = near[sector == d]
                if len(cand):
                    links.append((d, int(cand[np.argmin(np.linalg.norm(delta[cand], axis=1))])))
        trial = np.vstack([positions, here])
        proposed = [(m, v, int(EdgeKind.WALK), d) for d, v in links]
        proposed += [(v, m, int(EdgeKind.WALK), (d + 4) % 8) for d, v in links]
        arr = np.asarray(proposed, dtype=np.int64).reshape(-1, 4)
        ok = _verify(physics, trial, arr, params, lambda *a: None) if len(arr) else arr[:0, 0]
        good = arr[ok.astype(bool)] if len(arr) else arr
        if not len(good):
            stats.manual_dropped += 1
            continue
        positions = trial
        slot = {(e[0], e[3]): i for i, e in enumerate(edge_list)}
        for u, v, kind, d in good.tolist():
            existing = slot.get((u, d))
            if existing is None:
                edge_list.append((u, v, kind, d))
            elif np.linalg.norm(positions[v] - positions[u]) < np.linalg.norm(
                positions[edge_list[existing][1]] - positions[u]
            ):
                edge_list[existing] = (u, v, kind, d)
        stats.manual_added += 1
    return positions, np.asarray(edge_list, dtype=np.int64).reshape(-1, 4)
