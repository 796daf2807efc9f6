"""The nav's climbs in the lattice: an edge where the graph goes far round a step the nav joins.

A CS2 nav draws steep stairs as flat areas a few units deep (`decoy_cli/world/nav_climbs.py`);
the lattice, seldom landing a node on them, can miss a step players take every round and send
the replay the long way. After the capsule verification, the manual waypoints and the ladders,
each climb of the world (`World.meta["climbs"]`) whose two ends have a node nearby (within a
lattice spacing, a step in height) is joined by one edge, a JUMP up or a DROP down, in the
compass direction of the move (the nearest free one: a node has one edge per direction), when
the graph's shortest way between those nodes is more than `DETOUR` times their distance (or
missing). Where the lattice found the step, or a way round of a few strides, nothing is added.
As for a ladder, the capsule is not moved along the edge: the step face it crosses is where a
standing capsule does not fit.
"""

from __future__ import annotations

import numpy as np
from scipy.sparse import csr_matrix
from scipy.sparse.csgraph import dijkstra

from decoy_cli.waypoints.graph import EdgeKind
from decoy_cli.waypoints.ladders import end_node, free_direction
from decoy_cli.waypoints.lattice_params import LatticeParams

DETOUR = 5.0
"""A way round more than this many times the straight distance between a climb's two nodes is
not the way a player takes: the climb gets its own edge (a rule chosen, not measured)."""


def add_climb_edges(
    positions: np.ndarray, edges: np.ndarray, climbs_m: np.ndarray, params: LatticeParams
) -> tuple[np.ndarray, int]:
    """`edges` (E, 4: source, target, kind, direction) with an edge for each climb of
    `climbs_m` ((C, 6) start and end, metres) the graph goes far round (module docstring);
    returns (edges, climbs joined)."""
    rows = np.asarray(edges, dtype=np.int64).reshape(-1, 4)
    band = (-params.step_height, params.step_height)
    ends = [
        (
            end_node(positions, c[:3], band, params.spacing),
            end_node(positions, c[3:], band, params.spacing),
        )
        for c in climbs_m
    ]
    pairs = sorted({(s, t) for s, t in ends if s >= 0 and t >= 0 and s != t})
    if not pairs:
        return rows, 0
    length = np.linalg.norm(positions[rows[:, 1]] - positions[rows[:, 0]], axis=1)
    graph = csr_matrix((length, (rows[:, 0], rows[:, 1])), shape=(len(positions),) * 2)
    sources = sorted({s for s, _ in pairs})
    way = dijkstra(graph, indices=sources)
    row_of = {s: k for k, s in enumerate(sources)}
    used = {(int(s), int(d)) for s, d in rows[:, [0, 3]]}
    added = []
    for s, t in pairs:
        straight = float(np.linalg.norm(positions[t] - positions[s]))
        if way[row_of[s], t] <= DETOUR * straight:
            continue
        direction = free_direction(used, s, positions[t] - positions[s])
        if direction < 0:
            continue
        used.add((s, direction))
        kind = EdgeKind.JUMP if positions[t, 2] > positions[s, 2] else EdgeKind.DROP
        added.append([s, t, int(kind), direction])
    return np.concatenate([rows, np.asarray(added, dtype=np.int64).reshape(-1, 4)]), len(added)
