"""Stages 1 and 2 of the lattice: the breadth-first flood over the 0.7 m lattice with ray-tested
moves (walk, step, jump) and the one-way drops to lower floors (decoy_cli/waypoints/lattice.py).
"""

from __future__ import annotations

import numpy as np

from decoy_cli.waypoints.graph import DIRECTION_VECTORS, EdgeKind
from decoy_cli.waypoints.lattice_params import LatticeParams, Progress
from decoy_cli.world.physics import PhysicsWorld

BLOCKED = -1


class Lattice:
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


def evaluate_moves(
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


def flood(
    physics: PhysicsWorld,
    lattice: Lattice,
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
        kinds, target_z = evaluate_moves(physics, src, dirs, params)
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
