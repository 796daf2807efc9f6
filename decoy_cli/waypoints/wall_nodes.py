"""Wall nodes: a node toward each wall a lattice node cannot move to, as close as the capsule
allows (the project's addition to the paper's lattice; decoy_cli/waypoints/lattice.py).
"""

from __future__ import annotations

import numpy as np

from decoy_cli.waypoints.flood import BLOCKED, evaluate_moves
from decoy_cli.waypoints.graph import DIRECTION_VECTORS, EdgeKind
from decoy_cli.waypoints.lattice_params import LatticeParams
from decoy_cli.waypoints.verification import capsule_dims
from decoy_cli.world.physics import PhysicsWorld

_MIN_WALL_OFFSET_M = 0.15
"""A wall node nearer its parent than this adds no coverage worth an extra node."""


def add_wall_nodes(
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
    kinds, z = evaluate_moves(physics, positions[parent], direction, params, offset)
    level = (kinds == EdgeKind.WALK) | (kinds == EdgeKind.STEP)
    spot = np.column_stack(
        [positions[parent, :2] + DIRECTION_VECTORS[direction] * offset[:, None], np.nan_to_num(z)]
    )
    float_h, cap_h = capsule_dims(params)
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
