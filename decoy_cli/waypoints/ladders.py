"""Ladders in the lattice: seeds beside each ladder's ends, and a LADDER edge each way.

The lattice flood walks, steps, jumps and drops, so floors players reach only by climbing (de_nuke's
Heaven and roofs, de_train's sniper's nest) were never flooded, or were cut off when the
builder kept the largest strongly connected component. The map's ladders (`NavMesh.ladders`,
from the game's `.nav` file) close that gap in two steps of `build_lattice`:

1. `ladder_seeds`: a floor point beside each end of each ladder seeds the flood, so the floors
   at the top get nodes. An end's floor is the nearest one found by probes on rings around it
   (half a lattice spacing apart, out to `LADDER_REACH`), in a height band: a ladder's top lies
   up to a crouch-jump above the floor players step off onto (the ladder brush rises past the
   lip), its bottom a little above the floor.
2. `add_ladder_edges`: after the capsule verification and the manual waypoints, the nodes
   nearest the two ends (within `LADDER_REACH` spacings, in the same band) are joined by a
   LADDER edge each way, in the compass direction of the climb (the nearest free one: a node
   has one edge per direction). Where the two nodes are already joined, one edge per pair
   stays: a drop deeper than the safe fall becomes the ladder (a player climbs down rather than
   take the damage); any other edge is kept (it is the quicker way). An agent climbs the
   straight line between the nodes at the climbing speed; the capsule is not moved along it,
   since a climb passes over the lip, where a standing capsule does not fit.

A ladder whose ends find no floor (its top leads to a spot the nav mesh has no area for) gets
no edge; the build statistics count the ladders joined.
"""

from __future__ import annotations

import math

import numpy as np

from decoy_cli.csgo import HAMMER_TO_M, JUMP_HEIGHT_M, SAFE_DROP_M, STEP_HEIGHT_M
from decoy_cli.waypoints.graph import EdgeKind
from decoy_cli.waypoints.lattice_params import LatticeParams
from decoy_cli.world.physics import PhysicsWorld

LADDER_REACH = 2
"""How far from a ladder's end (horizontally, in lattice spacings) its floor node may lie: the
top's floor starts beyond the lip (`python benchmarks/studies/ladder_ends.py` lists each shipped
ladder's)."""
TOP_BAND_M = (-JUMP_HEIGHT_M, STEP_HEIGHT_M)
"""Heights of a top's floor relative to the ladder's top: down to a crouch-jump below (the brush
rising past the lip), up to a step above."""
BOTTOM_BAND_M = (-0.9, STEP_HEIGHT_M)
"""Heights of a bottom's floor relative to the ladder's bottom: chosen by hand just beyond the
deepest of the shipped ladders' (`python benchmarks/studies/ladder_ends.py`)."""
_ANGLES = np.arange(8) * (math.pi / 4)


def ladder_ends(ladders_u: np.ndarray) -> list[tuple[np.ndarray, tuple[float, float]]]:
    """Each ladder's top then bottom (metres) with its height band, in ladder order."""
    ends = []
    for ladder in np.asarray(ladders_u, dtype=np.float64).reshape(-1, 6) * HAMMER_TO_M:
        ends.append((ladder[:3], TOP_BAND_M))
        ends.append((ladder[3:], BOTTOM_BAND_M))
    return ends


def ladder_seeds(physics: PhysicsWorld, ladders_u: np.ndarray, params: LatticeParams) -> np.ndarray:
    """(S, 3) floor points (metres) beside the ends of the ladders (Hammer units, (L, 6) tops and
    bottoms), one per end that has a floor in its band; see the module docstring."""
    found = [end_floor(physics, end, band, params) for end, band in ladder_ends(ladders_u)]
    return np.asarray([f[0] for f in found if f is not None], dtype=np.float64).reshape(-1, 3)


def end_floor(
    physics: PhysicsWorld, end: np.ndarray, band: tuple[float, float], params: LatticeParams
) -> tuple[np.ndarray, float] | None:
    """The floor point nearest a ladder's `end` (metres) on rings around it, half a lattice
    spacing apart out to `LADDER_REACH` spacings, whose height relative to the end lies in
    `band`, with its ring's radius; None if there is none."""
    below, above = band
    for radius in np.arange(2 * LADDER_REACH + 1) * (params.spacing / 2):
        angles = _ANGLES[:1] if radius == 0.0 else _ANGLES
        probes = np.column_stack(
            [
                end[0] + radius * np.cos(angles),
                end[1] + radius * np.sin(angles),
                np.full(len(angles), end[2] + above + params.jump_height),
            ]
        )
        z, normal_z = physics.first_floor_below(probes, params.jump_height + above - below)
        ok = np.isfinite(z) & (normal_z >= params.min_floor_normal_z)
        ok &= (z >= end[2] + below) & (z <= end[2] + above)
        if ok.any():
            k = int(np.argmax(ok))
            return np.array([probes[k, 0], probes[k, 1], z[k]]), float(radius)
    return None


def add_ladder_edges(
    positions: np.ndarray, edges: np.ndarray, ladders_u: np.ndarray, params: LatticeParams
) -> tuple[np.ndarray, int]:
    """`edges` (E, 4: source, target, kind, direction) with a LADDER edge each way for every
    ladder whose two ends have a node (see the module docstring for nodes already joined);
    returns (edges, ladders joined)."""
    rows = np.asarray(edges, dtype=np.int64).reshape(-1, 4).tolist()
    used = {(s, d) for s, _, _, d in rows}
    joining = {(s, t): k for k, (s, t, _, _) in enumerate(rows)}
    reach = LADDER_REACH * params.spacing
    ends = ladder_ends(ladders_u)
    joined = 0
    for top_end, bottom_end in zip(ends[0::2], ends[1::2], strict=True):
        top = end_node(positions, *top_end, reach)
        bottom = end_node(positions, *bottom_end, reach)
        if top < 0 or bottom < 0 or top == bottom:
            continue
        ways = [(bottom, top), (top, bottom)]
        new = {
            (s, t): free_direction(used, s, positions[t] - positions[s])
            for s, t in ways
            if (s, t) not in joining
        }
        if any(d < 0 for d in new.values()):
            continue
        for s, t in ways:
            if (s, t) in new:
                used.add((s, new[s, t]))
                joining[s, t] = len(rows)
                rows.append([s, t, int(EdgeKind.LADDER), new[s, t]])
            elif rows[joining[s, t]][2] == EdgeKind.DROP and _hurts(positions, s, t):
                rows[joining[s, t]][2] = int(EdgeKind.LADDER)
        joined += 1
    return np.asarray(rows, dtype=np.int64).reshape(-1, 4), joined


def _hurts(positions: np.ndarray, source: int, target: int) -> bool:
    """Whether a drop from `source` to `target` is deeper than the safe fall."""
    return bool(positions[source, 2] - positions[target, 2] > SAFE_DROP_M)


def end_node(
    positions: np.ndarray, end: np.ndarray, band: tuple[float, float], reach: float
) -> int:
    """The node nearest `end` within `reach` horizontally and its height band (relative to
    `end`), -1 if none: a ladder's end, or a climb's (`climbs.py`)."""
    horizontal = np.hypot(positions[:, 0] - end[0], positions[:, 1] - end[1])
    dz = positions[:, 2] - end[2]
    ok = (horizontal <= reach) & (dz >= band[0]) & (dz <= band[1])
    if not ok.any():
        return -1
    distance = np.where(ok, np.hypot(horizontal, dz), np.inf)
    return int(np.argmin(distance))


def free_direction(used: set[tuple[int, int]], node: int, delta: np.ndarray) -> int:
    """The compass direction (0 = N = +y, clockwise) nearest `delta`'s that `node` has no edge
    in, -1 if it has all eight."""
    heading = math.degrees(math.atan2(delta[0], delta[1])) % 360.0
    preferred = round(heading / 45.0) % 8
    for offset in (0, 1, -1, 2, -2, 3, -3, 4):
        direction = (preferred + offset) % 8
        if (node, direction) not in used:
            return direction
    return -1
