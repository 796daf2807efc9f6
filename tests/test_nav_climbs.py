"""Climbs: the steps a CS2 nav connects that the lattice goes far round get an edge of their own
(decoy_cli/world/nav_climbs.py, decoy_cli/waypoints/climbs.py)."""

from __future__ import annotations

import json
import lzma
from pathlib import Path

import numpy as np
import pytest
from scipy.sparse import csr_matrix
from scipy.sparse.csgraph import dijkstra

from decoy_cli.csgo import HAMMER_TO_M
from decoy_cli.waypoints.build import build_graph
from decoy_cli.waypoints.climbs import DETOUR, add_climb_edges
from decoy_cli.waypoints.graph import EdgeKind, WaypointGraph
from decoy_cli.waypoints.lattice import LatticeParams
from decoy_cli.world.nav_climbs import nav_climbs
from decoy_cli.world.nav_json import read_nav
from decoy_cli.world.nav_polygons import polygon_world

CS2_NAV = Path(__file__).resolve().parents[1].parent / "shared/data/cs2_maps/de_dust2.nav.json.xz"


def rect(x0: float, y0: float, x1: float, y1: float, z: float) -> list[tuple[float, float, float]]:
    return [(x0, y0, z), (x1, y0, z), (x1, y1, z), (x0, y1, z)]


def write_nav(path: Path, areas: dict[int, list], links: list[tuple[int, int]]) -> Path:
    """An awpy JSON nav of `areas` (id: corners, Hammer units) with the directed `links`."""
    document = {
        "version": 35,
        "sub_version": 1,
        "is_analyzed": True,
        "areas": {
            str(k): {
                "area_id": k,
                "hull_index": 0,
                "dynamic_attribute_flags": 0,
                "corners": [{"x": x, "y": y, "z": z} for x, y, z in corners],
                "connections": [b for a, b in links if a == k],
                "ladders_above": [],
                "ladders_below": [],
            }
            for k, corners in areas.items()
        },
    }
    path.write_text(json.dumps(document))
    return path


# ---- the climbs of a nav ----------------------------------------------------------------------


def test_a_climb_is_a_connection_between_a_step_and_a_jump_across_a_small_gap(
    tmp_path: Path,
) -> None:
    areas = {
        1: rect(0, 0, 200, 100, 0),
        2: rect(0, 110, 200, 122, 30),  # a narrow step 30 u up across a 10 u hole: a climb
        3: rect(0, 122, 200, 200, 40),  # 10 u above 2: a step the lattice walks
        4: rect(0, 200, 200, 300, 110),  # 70 u above 3: beyond a jump
        5: rect(0, 340, 200, 400, 140),  # 30 u above 4 but 40 u away: beyond a hole
    }
    links = [(1, 2), (2, 1), (2, 3), (3, 4), (4, 5)]
    climbs = nav_climbs(read_nav(write_nav(tmp_path / "n.json", areas, links)))
    assert climbs.shape == (2, 6)
    up, down = climbs / HAMMER_TO_M
    assert np.allclose(up, [100, 100, 0, 100, 110, 30], atol=2.5)  # the middle, not a corner
    assert np.allclose(down, [100, 110, 30, 100, 100, 0], atol=2.5)


# ---- the climbs in a graph --------------------------------------------------------------------


def line_graph(count: int, spacing: float) -> tuple[np.ndarray, np.ndarray]:
    """Nodes on a line `spacing` apart, walked both ways."""
    positions = np.column_stack([np.arange(count) * spacing, np.zeros(count), np.zeros(count)])
    edges = [[k, k + 1, int(EdgeKind.WALK), 2] for k in range(count - 1)]
    edges += [[k + 1, k, int(EdgeKind.WALK), 6] for k in range(count - 1)]
    return positions, np.asarray(edges, dtype=np.int64)


def test_a_climb_gets_an_edge_only_where_the_graph_goes_far_round() -> None:
    params = LatticeParams()
    positions, edges = line_graph(12, 0.7)
    ledge = np.array([[0.0, 0.7, 0.8]])  # a node on a ledge above the first one
    positions = np.vstack([positions, ledge])
    top = len(positions) - 1
    # the ledge is reached from the far end of the line only: the way round is 11 strides
    edges = np.vstack([edges, [[11, top, int(EdgeKind.JUMP), 0], [top, 11, int(EdgeKind.DROP), 4]]])
    climb = np.array([[0.0, 0.1, 0.0, 0.0, 0.6, 0.8], [0.0, 0.6, 0.8, 0.0, 0.1, 0.0]])
    joined, count = add_climb_edges(positions, edges, climb, params)
    assert count == 2
    added = joined[len(edges) :]
    assert added[:, :3].tolist() == [[0, top, EdgeKind.JUMP], [top, 0, EdgeKind.DROP]]
    assert added[0, 3] == 0  # north, toward the ledge, free at node 0
    # a way round within DETOUR times the straight line: nothing is added
    near = np.vstack([edges, [[1, top, int(EdgeKind.JUMP), 0], [top, 1, int(EdgeKind.DROP), 5]]])
    straight = float(np.linalg.norm(positions[top] - positions[0]))
    assert 0.7 + np.linalg.norm(positions[top] - positions[1]) <= DETOUR * straight
    assert add_climb_edges(positions, near, climb, params)[1] == 0
    # no node near a climb's end: nothing is added
    far = climb + np.array([5.0, 0, 0, 5.0, 0, 0])
    assert add_climb_edges(positions, edges, far, params)[1] == 0


@pytest.mark.skipif(not CS2_NAV.is_file(), reason=f"{CS2_NAV} is absent (../shared/data)")
def test_the_stairs_from_under_a_to_a_are_climbed_from_their_landing(tmp_path: Path) -> None:
    """CS2 de_dust2's stairs between Under A and A (its own nav areas, 180 u around them): the
    lattice lands no node on the narrow first step from the landing players come up from, so
    without the climbs the landing cannot get back up and is pruned; with them it stays, with
    a way up to the A platform."""
    document = json.loads(lzma.decompress(CS2_NAV.read_bytes()))
    kept = {}
    for key, area in document["areas"].items():
        corners = np.array([[c["x"], c["y"]] for c in area["corners"]])
        if np.hypot(*(corners.mean(axis=0) - [650.0, 2360.0])) < 180.0:
            kept[key] = area
    ids = {int(k) for k in kept}
    for area in kept.values():
        area["connections"] = [c for c in area["connections"] if c in ids]
    path = tmp_path / "stairs.json"
    path.write_text(json.dumps({**document, "areas": kept}))
    nav = read_nav(path)
    # the shipped graph's lattice phase: its first seed, moved whole spacings onto the landing
    first = np.array([-30.241875, -16.906875])
    landing = np.array([657.0, 2346.0, 4.0]) * HAMMER_TO_M
    on_landing = first + np.round((landing[:2] - first) / 0.7) * 0.7
    seeds = np.array([[*on_landing, landing[2]], np.array([626.0, 2412.0, 130.0]) * HAMMER_TO_M])

    def built(with_climbs: bool) -> WaypointGraph:
        world = polygon_world(nav, "de_dust2")
        if not with_climbs:
            del world.meta["climbs"]
        return build_graph(world, "de_dust2", seeds, LatticeParams())[0]

    def way_up(graph: WaypointGraph) -> tuple[float, float, float]:
        """(metres from the landing to its nearest node, the way from that node up to A, the
        straight line from it to A's nearest node)."""
        start = int(np.argmin(np.linalg.norm(graph.positions - landing, axis=1)))
        length = np.linalg.norm(
            graph.positions[graph.edge_target] - graph.positions[graph.edge_source], axis=1
        )
        shape = (graph.num_nodes, graph.num_nodes)
        ways = dijkstra(csr_matrix((length, (graph.edge_source, graph.edge_target)), shape=shape))
        top = graph.positions[:, 2] > 120.0 * HAMMER_TO_M
        straight = np.linalg.norm(graph.positions[top] - graph.positions[start], axis=1).min()
        off = np.linalg.norm(graph.positions[start] - landing)
        return float(off), float(ways[start, top].min()), float(straight)

    graph = built(with_climbs=True)
    assert graph.meta["climbs_joined"] > 0
    off, way, straight = way_up(graph)
    assert off < 0.1 and way < 2 * straight
    off_without, _, _ = way_up(built(with_climbs=False))
    assert off_without > 0.5  # the test's premise: the lattice alone loses the landing
