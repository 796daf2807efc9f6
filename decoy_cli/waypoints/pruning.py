"""After the lattice: the largest strongly connected component, a fixed node order, and manual
waypoints merged in (decoy_cli/waypoints/lattice.py).
"""

from __future__ import annotations

import numpy as np
from scipy.sparse import csr_matrix
from scipy.sparse.csgraph import connected_components

from decoy_cli.errors import GraphError
from decoy_cli.waypoints.graph import EdgeKind
from decoy_cli.waypoints.lattice_params import BuildStats, LatticeParams
from decoy_cli.waypoints.verification import verify_edges
from decoy_cli.world.physics import PhysicsWorld


def prune(positions: np.ndarray, edges: np.ndarray, stats: BuildStats):
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


def canonical_order(positions: np.ndarray, edges: np.ndarray):
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


def merge_manual(
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
        ok = verify_edges(physics, trial, arr, params, lambda *a: None) if len(arr) else arr[:0, 0]
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
