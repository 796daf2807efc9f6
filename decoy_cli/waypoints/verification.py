"""Stage 3 of the lattice: a capsule moved along every edge in pybullet; nodes where it does not
fit are nudged to where it does (decoy_cli/waypoints/lattice.py).
"""

from __future__ import annotations

import numpy as np

from decoy_cli.waypoints.graph import EdgeKind
from decoy_cli.waypoints.lattice_params import LatticeParams, Progress
from decoy_cli.world.physics import PhysicsWorld


def capsule_dims(params: LatticeParams) -> tuple[float, float]:
    """(height above the floor of the capsule's bottom, capsule height)."""
    float_h = params.step_height + params.verify_clearance
    return float_h, params.agent_height - float_h


def nudge_nodes(
    physics: PhysicsWorld, positions: np.ndarray, params: LatticeParams
) -> tuple[np.ndarray, int]:
    """Move nodes where the capsule does not fit (too close to a wall or ledge face) to the
    nearest spot within `max_nudge` where it does, on the same floor; returns the new positions
    and how many moved. Nodes with no such spot stay, and verification removes their edges."""
    float_h, cap_h = capsule_dims(params)
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


def verify_edges(
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
    float_h, cap_height = capsule_dims(params)
    centres, owner = [], []
    for e in range(len(edges)):
        t = np.linspace(0.0, 1.0, n_steps[e] + 1)
        xy = src[e, :2] + t[:, None] * (dst[e, :2] - src[e, :2])
        if kind[e] == EdgeKind.JUMP:
            base = np.full_like(t, max(src[e, 2], dst[e, 2]))
        elif kind[e] == EdgeKind.DROP:
            base = np.full_like(t, src[e, 2])
            falls = max(1, int(np.ceil((src[e, 2] - dst[e, 2]) / params.verify_step)))
            fall = np.linspace(src[e, 2], dst[e, 2], falls + 1)[1:]  # the fall, in as fine steps
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
