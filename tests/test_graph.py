"""WaypointGraph: file round-trip and its failures, floor-aware nearest, shortest paths, actions."""

from __future__ import annotations

import json
import warnings
from pathlib import Path

import numpy as np
import pytest

from decoy_cli.errors import GraphError, OutputError
from decoy_cli.waypoints.graph import (
    DIRECTION_NAMES,
    DIRECTION_VECTORS,
    FORMAT_VERSION,
    SNAP_MAX_ABOVE_M,
    SNAP_MAX_BELOW_M,
    STOP_ACTION,
    EdgeKind,
    WaypointGraph,
    write_npz_atomic,
)
from decoy_cli.waypoints.quality import snap_quality

N, NE, E, SE, S, SW, W, NW = range(8)


def make_graph(positions, edges, **extra) -> WaypointGraph:
    """A graph from positions and (source, target, kind, direction) rows."""
    positions = np.asarray(positions, dtype=np.float64)
    edges = np.asarray(edges, dtype=np.int64).reshape(-1, 4)
    fields = {
        "node_place": np.full(len(positions), -1, np.int16),
        "place_names": [],
        "regions": {},
    }
    fields.update(extra)
    return WaypointGraph(
        positions=positions,
        edge_source=edges[:, 0].astype(np.int32),
        edge_target=edges[:, 1].astype(np.int32),
        edge_kind=edges[:, 2].astype(np.uint8),
        edge_direction=edges[:, 3].astype(np.uint8),
        **fields,
    )


def small_graph() -> WaypointGraph:
    """Five nodes, hand-checkable paths (metres):

        3 (1,1)
       /|  \\
      0 - 1 - 2      4 (0,5): leaves to 0 only, never reached
    (0,0) (1,0) (2,0)

    0<->1, 1<->2, 1<->3 (N/S), 0->3 (NE), 3->0 (SW), 3->2 (SE, one way), 4->0 (S), and a drop
    2->... none: 2 only goes back to 1.
    """
    walk, drop = int(EdgeKind.WALK), int(EdgeKind.DROP)
    return make_graph(
        [(0, 0, 0), (1, 0, 0), (2, 0, 0), (1, 1, 0), (0, 5, 0)],
        [
            (0, 1, walk, E),
            (1, 0, walk, W),
            (1, 2, walk, E),
            (2, 1, walk, W),
            (1, 3, walk, N),
            (3, 1, walk, S),
            (0, 3, walk, NE),
            (3, 0, walk, SW),
            (3, 2, walk, SE),
            (4, 0, drop, S),
        ],
        node_place=np.array([0, 0, 1, 1, -1], np.int16),
        place_names=["TSpawn", "BombsiteA"],
        regions={"t_spawn": np.array([0, 1]), "bombsite_a": np.array([2, 3])},
        meta={"map": "de_dust2", "stats": {"nodes": 5}, "note": "hand-made"},
    )


def two_floor_graph() -> WaypointGraph:
    """A 5 x 5 grid (1 m) on the ground (z = 0) and the same grid on a floor 4 m above."""
    xs, ys = np.meshgrid(np.arange(5.0), np.arange(5.0), indexing="ij")
    ground = np.column_stack([xs.ravel(), ys.ravel(), np.zeros(25)])
    upper = ground + np.array([0.0, 0.0, 4.0])
    return make_graph(np.vstack([ground, upper]), [])


# ---- file format -------------------------------------------------------------------------------


def test_save_load_round_trip(tmp_path: Path) -> None:
    graph = small_graph()
    graph.save(tmp_path / "g.npz")
    loaded = WaypointGraph.load(tmp_path / "g.npz")
    for name in ("positions", "edge_source", "edge_target", "edge_kind", "edge_direction"):
        np.testing.assert_array_equal(getattr(loaded, name), getattr(graph, name))
    np.testing.assert_array_equal(loaded.node_place, graph.node_place)
    assert loaded.positions.dtype == np.float64 and loaded.edge_source.dtype == np.int32
    assert loaded.place_names == graph.place_names
    assert loaded.regions.keys() == graph.regions.keys()
    for name, nodes in graph.regions.items():
        np.testing.assert_array_equal(loaded.region_of(name), nodes)
    assert loaded.meta == graph.meta
    assert loaded.shortest_path(0, 2) == graph.shortest_path(0, 2)


def test_saves_are_byte_identical(tmp_path: Path) -> None:
    small_graph().save(tmp_path / "a.npz")
    small_graph().save(tmp_path / "b.npz")
    WaypointGraph.load(tmp_path / "a.npz").save(tmp_path / "c.npz")
    data = (tmp_path / "a.npz").read_bytes()
    assert data == (tmp_path / "b.npz").read_bytes() == (tmp_path / "c.npz").read_bytes()
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a.npz", "b.npz", "c.npz"]


def test_save_overwrites_and_refuses_a_directory(tmp_path: Path) -> None:
    target = tmp_path / "g.npz"
    target.write_bytes(b"old")
    small_graph().save(target)
    assert WaypointGraph.load(target).num_nodes == 5
    (tmp_path / "dir.npz").mkdir()
    with pytest.raises(OutputError, match="directory"):
        small_graph().save(tmp_path / "dir.npz")
    blocker = tmp_path / "file"
    blocker.write_text("x")
    with pytest.raises(OutputError, match="cannot write"):
        small_graph().save(blocker / "g.npz")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["dir.npz", "file", "g.npz"]


def test_load_missing_file(tmp_path: Path) -> None:
    with pytest.raises(GraphError, match="not found"):
        WaypointGraph.load(tmp_path / "nope.npz")


@pytest.mark.parametrize(
    "damage",
    [
        pytest.param(lambda data: b"not a zip file at all", id="garbage"),
        pytest.param(lambda data: b"", id="empty"),
        pytest.param(lambda data: data[: len(data) // 2], id="truncated-half"),
        pytest.param(lambda data: data[:-1], id="truncated-last-byte"),
    ],
)
def test_load_corrupt_or_truncated(tmp_path: Path, damage) -> None:
    small_graph().save(tmp_path / "g.npz")
    path = tmp_path / "g.npz"
    path.write_bytes(damage(path.read_bytes()))
    with pytest.raises(GraphError, match="not a readable waypoint graph"):
        WaypointGraph.load(path)


def test_load_flipped_bytes_always_graph_error(tmp_path: Path) -> None:
    """Damage anywhere (the compressed data included, where zlib itself fails) is a GraphError
    or, where it hits a field nothing reads, the same graph: never another exception."""
    graph = small_graph()
    graph.save(tmp_path / "g.npz")
    data = (tmp_path / "g.npz").read_bytes()
    rng = np.random.default_rng(7)
    path = tmp_path / "damaged.npz"
    errors = 0
    for start in rng.integers(0, len(data) - 4, size=150):
        damaged = bytearray(data)
        damaged[start : start + 4] = bytes(b ^ 0x5A for b in damaged[start : start + 4])
        path.write_bytes(bytes(damaged))
        try:
            loaded = WaypointGraph.load(path)
        except GraphError:
            errors += 1
            continue
        np.testing.assert_array_equal(loaded.positions, graph.positions)
        np.testing.assert_array_equal(loaded.edge_target, graph.edge_target)
    assert errors > 100


def _arrays(graph: WaypointGraph, path: Path) -> dict[str, np.ndarray]:
    graph.save(path)
    with np.load(path) as data:
        return {name: data[name] for name in data.files}


@pytest.mark.parametrize(
    ("change", "message"),
    [
        ({"format_version": np.array(FORMAT_VERSION + 1, np.int32)}, "format version 2"),
        ({"format_version": np.array([1, 1], np.int32)}, "not a readable"),
        ({"regions": np.array(json.dumps([1, 2]))}, "not a readable"),
        ({"place_names": np.array(json.dumps(5))}, "not a readable"),
        ({"meta": np.array("{")}, "not a readable"),
        ({"positions": np.zeros(5)}, r"corrupt waypoint graph \(positions are not"),
        ({"positions": np.full((5, 3), np.nan)}, "positions hold NaN"),
        ({"edge_target": np.array([0, 1, 9, 1, 3, 1, 3, 0, 2, 0], np.int32)}, "outside the node"),
        ({"edge_kind": np.zeros(3, np.uint8)}, "differ in length"),
        ({"node_place": np.zeros(2, np.int16)}, "node_place length"),
    ],
)
def test_load_rejects_bad_members(tmp_path: Path, change: dict, message: str) -> None:
    arrays = _arrays(small_graph(), tmp_path / "g.npz")
    write_npz_atomic(tmp_path / "bad.npz", {**arrays, **change})
    with pytest.raises(GraphError, match=message):
        WaypointGraph.load(tmp_path / "bad.npz")


def test_load_rejects_missing_member_and_pickles(tmp_path: Path) -> None:
    arrays = _arrays(small_graph(), tmp_path / "g.npz")
    del arrays["positions"]
    write_npz_atomic(tmp_path / "missing.npz", arrays)
    with pytest.raises(GraphError, match="positions"):
        WaypointGraph.load(tmp_path / "missing.npz")
    np.savez(tmp_path / "pickle.npz", format_version=np.array([{"a": 1}], dtype=object))
    with pytest.raises(GraphError, match="not a readable"):
        WaypointGraph.load(tmp_path / "pickle.npz")


# ---- nearest -----------------------------------------------------------------------------------


def brute_nearest(graph: WaypointGraph, points: np.ndarray) -> np.ndarray:
    """Nearest waypoint within the vertical band, by checking every node."""
    dz = graph.positions[None, :, 2] - points[:, None, 2]
    dist = np.linalg.norm(graph.positions[None] - points[:, None], axis=2)
    dist[(dz > SNAP_MAX_ABOVE_M) | (dz < -SNAP_MAX_BELOW_M)] = np.inf
    best = np.argmin(dist, axis=1)
    return np.where(np.isfinite(dist[np.arange(len(points)), best]), best, -1)


def test_nearest_vectorised_matches_brute_force() -> None:
    graph = two_floor_graph()
    rng = np.random.default_rng(3)
    floor = rng.choice([0.0, 4.0], size=400)
    points = np.column_stack(
        [
            rng.uniform(-0.5, 4.5, 400),
            rng.uniform(-0.5, 4.5, 400),
            floor + rng.uniform(-0.4, 1.1, 400),
        ]
    )
    index, distance = graph.nearest(points)
    np.testing.assert_array_equal(index, brute_nearest(graph, points))
    np.testing.assert_allclose(graph.positions[index, 2], floor)
    np.testing.assert_allclose(distance, np.linalg.norm(graph.positions[index] - points, axis=1))


def test_nearest_is_floor_aware() -> None:
    graph = two_floor_graph()
    index, _ = graph.nearest(np.array([[2.1, 2.0, 0.1], [2.1, 2.0, 4.1], [2.1, 2.0, 5.2]]))
    assert graph.positions[index, 2].tolist() == [0.0, 4.0, 4.0]
    # between the floors: more than the band from both, so no waypoint
    index, distance = graph.nearest(np.array([[2.0, 2.0, 2.0]]))
    assert index.tolist() == [-1] and np.isinf(distance[0])
    # just under the upper floor (a player on the ground jumping) stays on the ground
    index, _ = graph.nearest(np.array([2.0, 2.0, 1.2]))
    assert graph.positions[index[0], 2] == 0.0


def test_nearest_single_point_and_max_distance() -> None:
    graph = two_floor_graph()
    index, distance = graph.nearest(np.array([1.2, 3.1, 0.0]))
    assert index.shape == (1,) and distance.shape == (1,)
    np.testing.assert_allclose(graph.positions[index[0]], [1.0, 3.0, 0.0])
    np.testing.assert_allclose(distance[0], np.hypot(0.2, 0.1))
    far = np.array([[20.0, 20.0, 0.0], [4.3, 4.0, 0.0]])
    index, distance = graph.nearest(far, max_distance=0.5)
    assert index.tolist() == [-1, 24] and np.isinf(distance[0])


@pytest.mark.parametrize(
    "points",
    [np.array([[0.0, np.nan, 0.0]]), np.array([0.0, 0.0, np.inf]), np.zeros((2, 2))],
    ids=["nan", "inf", "bad-shape"],
)
def test_nearest_rejects_bad_points(points: np.ndarray) -> None:
    with pytest.raises(GraphError, match="nearest"):
        two_floor_graph().nearest(points)


def test_nearest_on_a_graph_smaller_than_the_candidate_count() -> None:
    graph = make_graph([(0, 0, 0), (3, 0, 0)], [])
    index, _ = graph.nearest(np.array([[2.9, 0.0, 0.0], [0.1, 0.0, 0.0]]))
    assert index.tolist() == [1, 0]


# ---- paths, actions ----------------------------------------------------------------------------


def test_shortest_path_hand_checked() -> None:
    graph = small_graph()
    assert graph.shortest_path(0, 2) == [0, 1, 2]  # 2 m, not 0-3-2 (2.83 m)
    assert graph.shortest_path(2, 3) == [2, 1, 3]  # 3->2 is one way
    assert graph.shortest_path(3, 2) == [3, 2]
    assert graph.shortest_path(4, 2) == [4, 0, 1, 2]
    assert graph.shortest_path(1, 1) == [1]
    dist, _ = graph.path_lengths(0)
    np.testing.assert_allclose(dist[:4], [0.0, 1.0, 2.0, np.sqrt(2)])
    assert np.isinf(dist[4])


def test_shortest_path_unreachable_raises() -> None:
    with pytest.raises(GraphError, match="cannot be reached"):
        small_graph().shortest_path(0, 4)


def test_shortest_path_finds_a_long_detour() -> None:
    """Two nodes 1 m apart joined only by a 21 m loop: beyond the first, bounded search."""
    walk = int(EdgeKind.WALK)
    graph = make_graph(
        [(0, 0, 0), (1, 0, 0), (0, 5, 0), (0, 10, 0), (1, 10, 0), (1, 5, 0)],
        [(0, 2, walk, N), (2, 3, walk, N), (3, 4, walk, E), (4, 5, walk, S), (5, 1, walk, S)],
    )
    assert graph.shortest_path(0, 1) == [0, 2, 3, 4, 5, 1]
    np.testing.assert_allclose(graph.edge_length.sum(), 21.0)


def test_out_edges_and_action_mask() -> None:
    graph = small_graph()
    table = graph.out_edges
    assert table.shape == (5, 8)
    assert {d: int(e) for d, e in enumerate(table[1]) if e >= 0} == {N: 4, E: 2, W: 1}
    for node, direction in zip(*np.nonzero(table >= 0), strict=True):
        edge = table[node, direction]
        assert graph.edge_source[edge] == node and graph.edge_direction[edge] == direction
    assert (table >= 0).sum() == graph.num_edges
    assert graph.action_mask(1).tolist() == [1, 0, 1, 0, 0, 0, 1, 0, 1]
    assert graph.action_mask(2).tolist() == [0, 0, 0, 0, 0, 0, 1, 0, 1]
    assert graph.action_mask(4)[STOP_ACTION] == 1 and graph.action_mask(4)[S] == 1


def test_direction_tables_follow_the_compass() -> None:
    """N = +y, E = +x, numbered clockwise."""
    assert DIRECTION_NAMES[N] == "N" and DIRECTION_NAMES[E] == "E"
    assert DIRECTION_VECTORS[N].tolist() == [0, 1]
    assert DIRECTION_VECTORS[E].tolist() == [1, 0]
    assert DIRECTION_VECTORS[SW].tolist() == [-1, -1]
    headings = np.degrees(np.arctan2(DIRECTION_VECTORS[:, 0], DIRECTION_VECTORS[:, 1])) % 360
    np.testing.assert_allclose(headings, 45.0 * np.arange(8))


def test_adjacency_and_regions() -> None:
    graph = small_graph()
    assert graph.adjacency.shape == (5, 5)
    np.testing.assert_allclose(graph.adjacency[0, 3], np.sqrt(2))
    assert graph.adjacency[2, 3] == 0  # 3->2 only
    np.testing.assert_array_equal(graph.region_of("bombsite_a"), [2, 3])
    with pytest.raises(GraphError, match="unknown region 'mid'"):
        graph.region_of("mid")


def test_snap_quality_with_unsnapped_positions() -> None:
    """Positions with no waypoint on their floor count as unsnapped and push p95 to inf."""
    graph = two_floor_graph()
    on_floor = np.array([[1.1, 1.0, 0.0], [2.0, 2.3, 4.1], [3.0, 3.0, 0.2]])
    quality = snap_quality(graph, on_floor)
    assert quality.unsnapped == 0 and quality.within_horizontal == 1.0
    np.testing.assert_allclose(quality.median_horizontal, 0.1)
    between = np.array([[2.0, 2.0, 2.0]] * 2)  # between the floors: no waypoint
    quality = snap_quality(graph, np.vstack([on_floor, between]))
    assert quality.unsnapped == 2 and quality.p95_horizontal == np.inf
    assert quality.within_horizontal == pytest.approx(0.6)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        quality = snap_quality(graph, between)
    assert quality.p95_3d == np.inf and np.isnan(quality.median_3d)
    assert quality.within_3d == 0.0


def test_snap_quality_on_the_ground() -> None:
    """With the floor under each position, the airborne ones are counted and left out of the
    grounded share: a jump 1 m up is 1 m from its waypoint, not a gap in the graph."""
    graph = two_floor_graph()
    positions = np.array([[1.1, 1.0, 0.0], [3.0, 3.0, 0.2], [1.0, 1.0, 1.0], [1.0, 1.0, 0.9]])
    floor = np.array([0.0, 0.0, 0.0, np.nan])  # the last floor is unknown: counted as ground
    quality = snap_quality(graph, positions, floor_z=floor)
    assert quality.airborne == 1
    assert quality.within_3d == pytest.approx(0.5)
    assert quality.grounded_within_3d == pytest.approx(2 / 3)
    assert snap_quality(graph, positions).airborne is None
