"""Build the waypoint graph of a world: the paper's three stages, then pruning and manual points.

1. **Lattice (BFS).** From seed points, a breadth-first flood over a square lattice (0.7 m) in the
   8 compass directions. A move to a neighbour is tested with rays in the physics world: a ray
   down finds the neighbour's floor; rays down along the edge sample the floor profile (so a ramp,
   whose height change over a 0.99 m diagonal can exceed the step height, is told from a ledge);
   a ray up checks headroom; nine rays at the capsule's centre line and edges, at knee, waist and
   head height, check the body's way. Moves become walk, step (ledge up to 18 u) or jump (up to a
   crouch-jump) edges, in both directions where both pass.
2. **Drop pass.** Moves whose profile falls by more than the step height (down to `max_drop`, the
   deepest fall a player at full health survives; below the safe fall it costs health in the
   simulator) become one-way drop edges; lower floors first found this way are flooded too.
   **Wall nodes** (the project's addition, `wall_nodes`): where a node has no level move in a
   cardinal direction (a wall, a railing, a cliff edge, the face of a box it jumps onto), a node
   is added toward it, as close as the capsule allows, if the floor continues on the same level
   and the capsule fits there, linked to its parent both ways and to the wall nodes of its
   lattice neighbours along the wall; a jump or drop the parent had that way now leaves from the
   wall node. Players hug walls and wait at box faces: on the pure lattice such a position can
   be up to 0.7 m from every node (`decoy build-waypoints --check-esta` measures how many real
   positions each graph covers). Each node still has at most one edge per direction.
3. **Verification.** A capsule is moved along every edge in pybullet (a drop's fall included), in
   steps of at most 0.1 m, floating the step height above the floor (as the simulator moves agents);
   an edge along which it would penetrate the world is removed. First (before wall nodes are placed,
   so that they stand against the final positions), a node where the capsule does not fit (a lattice
   point that happens to lie too close to a wall) is moved up to 0.3 m to where it fits, instead of
   being lost: without that, a quarter of the lattice's edges near walls die. The capsule is 20%
   thinner than the CS:GO hull (radius 12.8 u, not 16 u): the nav world's walls stand up to 16 u
   beyond the nav edge, often less where areas face each other across narrow gaps, and the thinner
   capsule tolerates that approximation (with the full radius, measurably fewer nodes end up in the
   largest strongly connected component).

**Ladders** (`ladders.py`): the map's ladders seed the flood beside their ends, and after the
verification and the manual waypoints the nodes at a ladder's two ends are joined by a LADDER
edge each way. **Climbs** (`climbs.py`): a CS2 nav's steps of more than a step height that the
graph goes far round get an edge of their own.

Then the graph is pruned to its largest strongly connected component (so an agent can always get
back), manual waypoints are merged in, each node gets its nav place, and nodes are numbered in a
fixed order so the same inputs give the same file.

The stages live in their own modules: flood.py (1, 2), wall_nodes.py, verification.py (3),
pruning.py; the parameters and statistics in lattice_params.py. This module runs them in order.
"""

from __future__ import annotations

import time

import numpy as np

from decoy_cli.errors import GraphError
from decoy_cli.waypoints.climbs import add_climb_edges
from decoy_cli.waypoints.flood import Lattice, flood
from decoy_cli.waypoints.graph import DIRECTION_VECTORS, EdgeKind
from decoy_cli.waypoints.ladders import add_ladder_edges, ladder_seeds
from decoy_cli.waypoints.lattice_params import BuildStats, LatticeParams, LatticeResult, Progress
from decoy_cli.waypoints.pruning import canonical_order, merge_manual, prune
from decoy_cli.waypoints.verification import nudge_nodes, verify_edges
from decoy_cli.waypoints.wall_nodes import add_wall_nodes
from decoy_cli.world.physics import PhysicsWorld

__all__ = ["BuildStats", "LatticeParams", "LatticeResult", "Progress", "build_lattice"]


def _kind_counts(kinds: np.ndarray) -> dict[str, int]:
    return {k.name.lower(): int(np.sum(kinds == k)) for k in EdgeKind}


def _cell_on_floor(
    physics: PhysicsWorld, lattice: Lattice, point: np.ndarray, params: LatticeParams
) -> tuple[tuple[int, int], float] | None:
    """The lattice cell at or next to `point` whose floor is the point's own floor (within
    `same_floor_dz`; a cell's centre can lie off a ledge the point stands on), with that floor's
    height; None when no such cell is found."""
    ci, cj = lattice.cell(point[:2])
    cells = [(ci, cj)] + [(ci + int(di), cj + int(dj)) for di, dj in DIRECTION_VECTORS]
    probes = np.array([[*lattice.xy(c), point[2] + params.jump_height] for c in cells])
    z, nz = physics.first_floor_below(probes, params.jump_height + params.same_floor_dz)
    ok = np.isfinite(z) & (nz >= params.min_floor_normal_z)
    ok &= np.abs(z - point[2]) <= params.same_floor_dz
    if not ok.any():
        return None
    k = int(np.argmax(ok))
    return cells[k], float(z[k])


def build_lattice(
    physics: PhysicsWorld,
    seeds: np.ndarray,
    params: LatticeParams = LatticeParams(),
    manual: np.ndarray | None = None,
    progress: Progress = lambda stage, done, total: None,
    ladders_u: np.ndarray | None = None,
    climbs_m: np.ndarray | None = None,
) -> LatticeResult:
    """Run the three stages, prune, merge manual waypoints; see the module docstring. `ladders_u`:
    the map's ladders, (L, 6) top and bottom x y z in Hammer units (`NavMesh.ladders`);
    `climbs_m`: the world's climbs, (C, 6) start and end in metres (`climbs.py`)."""
    stats = BuildStats()
    seeds = np.asarray(seeds, dtype=np.float64).reshape(-1, 3)
    if len(seeds) == 0:
        raise GraphError("no seed points: give at least one position on a floor")
    ladders = np.zeros((0, 6)) if ladders_u is None else np.asarray(ladders_u).reshape(-1, 6)
    lattice = Lattice(seeds[0], params)

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
    stats.ladders = len(ladders)
    for seed in ladder_seeds(physics, ladders, params):
        found = _cell_on_floor(physics, lattice, seed, params)
        if found is None:
            continue
        stats.ladder_seeds += 1
        node, new = lattice.find_or_add(*found)
        if new:
            frontier.append(node)
    stats.seeds = len(seeds)
    edges: list[tuple[int, int, int, int]] = []
    drops: list[tuple[int, int, float]] = []
    flood(physics, lattice, frontier, params, edges, drops, progress, "lattice")
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
        flood(physics, lattice, new_nodes, params, edges, drops, progress, "drop pass")
    stats.seconds["drop pass"] = time.perf_counter() - clock

    # stage 3: verification with a moving capsule; its nudges come first (module docstring)
    clock = time.perf_counter()
    positions, stats.nudged_nodes = nudge_nodes(physics, np.asarray(lattice.positions), params)
    nudge_seconds = time.perf_counter() - clock
    if params.wall_nodes:
        clock = time.perf_counter()
        positions, edges = add_wall_nodes(physics, positions, edges, params)
        stats.wall_nodes = len(positions) - len(lattice.positions)
        stats.seconds["wall nodes"] = time.perf_counter() - clock
    clock = time.perf_counter()
    edge_arr = np.asarray(edges, dtype=np.int64).reshape(-1, 4)
    keep = verify_edges(physics, positions, edge_arr, params, progress)
    removed = edge_arr[~keep]
    removed_segments = np.stack([positions[removed[:, 0]], positions[removed[:, 1]]], axis=1)
    stats.verified_removed = _kind_counts(removed[:, 2])
    edge_arr = edge_arr[keep]
    stats.seconds["verification"] = nudge_seconds + time.perf_counter() - clock

    # manual waypoints, the ladders, then the largest strongly connected component
    clock = time.perf_counter()
    if manual is not None and len(manual):
        positions, edge_arr = merge_manual(physics, positions, edge_arr, manual, params, stats)
    edge_arr, stats.ladders_joined = add_ladder_edges(positions, edge_arr, ladders, params)
    climbs_joined = 0
    if climbs_m is not None:
        edge_arr, climbs_joined = add_climb_edges(positions, edge_arr, climbs_m, params)
    positions, edge_arr, pruned = prune(positions, edge_arr, stats)
    positions, edge_arr = canonical_order(positions, edge_arr)
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
        climbs_joined=climbs_joined,
    )
