"""Line of sight compared between worlds: hand-made walls, pair sampling, placement, plots."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from worlds import box, floor, quad, wall

from decoy_cli.csgo import EYE_HEIGHT_M
from decoy_cli.errors import GraphError, OutputError, WorldError
from decoy_cli.waypoints.build import builtin_graph
from decoy_cli.waypoints.graph import WaypointGraph
from decoy_cli.waypoints.los_pairs import disagreement_by_place, eye_pairs, random_node_pairs
from decoy_cli.world.los import (
    LosComparison,
    check_placement,
    compare_line_of_sight,
    plot_los_comparison,
    sideways,
)
from decoy_cli.world.meshfile import read_mesh
from decoy_cli.world.navmesh import nav_world
from decoy_cli.world.physics import PhysicsWorld
from decoy_cli.world.world import World

DATA = Path(__file__).resolve().parents[1].parent / "shared" / "data"
MOH_TRI = DATA / "meshes" / "de_dust2_moh-maps.tri"

EYE = 1.2
WALL_TOP = 3.0
# a wall on x = 0.05 from y = -5 to 5 (off the pairs' grid, so no ray ends on a triangle)
CROSSING = [(-3.0, 0.0, EYE), (3.0, 0.0, EYE)]  # through the wall
SAME_SIDE = [(-3.0, -2.0, EYE), (-3.0, 2.0, EYE)]  # west of the wall
OVER = [(-3.0, 0.0, WALL_TOP + 1.0), (3.0, 0.0, WALL_TOP + 1.0)]  # above the wall
AROUND = [(-3.0, 6.0, EYE), (3.0, 6.0, EYE)]  # north of the wall's end
PAIRS = np.array([CROSSING, SAME_SIDE, OVER, AROUND])


def _world(with_wall: bool, name: str) -> World:
    parts = [floor(-10.0, -10.0, 10.0, 10.0)]
    if with_wall:
        parts.append(wall(0.05, -5.0, 0.05, 5.0, 0.0, WALL_TOP))
    return World(np.concatenate(parts), name=name, source=f"hand-made {name}")


def test_a_wall_between_two_points_blocks_in_both_worlds_and_they_agree() -> None:
    result = compare_line_of_sight(_world(True, "a"), _world(True, "b"), PAIRS)
    assert result.visible_a.tolist() == [False, True, True, True]
    assert result.visible_b.tolist() == [False, True, True, True]
    assert result.agreement == 1.0
    assert result.confusion == {"both": 3, "only_a": 0, "only_b": 0, "neither": 1}
    assert (result.name_a, result.name_b) == ("a", "b")


def test_a_wall_missing_in_one_world_is_counted_for_the_world_that_sees() -> None:
    with_wall, without = _world(True, "walled"), _world(False, "open")
    result = compare_line_of_sight(with_wall, without, PAIRS)
    assert result.confusion == {"both": 3, "only_a": 0, "only_b": 1, "neither": 0}
    assert result.agree.tolist() == [False, True, True, True]
    assert result.agreement == 0.75
    swapped = compare_line_of_sight(without, with_wall, PAIRS)
    assert swapped.confusion == {"both": 3, "only_a": 1, "only_b": 0, "neither": 0}
    crossing = result.subset(np.array([True, False, False, False]))
    assert crossing.num_pairs == 1 and crossing.agreement == 0.0
    assert crossing.summary()["only_b"] == 1


def test_world_b_can_test_its_own_points_for_the_same_pairs() -> None:
    raised = PAIRS.copy()
    raised[0, :, 2] = WALL_TOP + 1.0  # in B the crossing pair looks over the wall
    result = compare_line_of_sight(_world(True, "a"), _world(True, "b"), PAIRS, raised)
    assert result.confusion == {"both": 3, "only_a": 0, "only_b": 1, "neither": 0}
    np.testing.assert_array_equal(result.pairs_b, raised)


def test_an_open_physics_world_is_borrowed_and_left_open() -> None:
    with PhysicsWorld(_world(True, "a")) as physics:
        result = compare_line_of_sight(physics, _world(False, "b"), PAIRS)
        assert physics._p.isConnected(physics.client)
        assert result.name_a == "a"
        assert result.confusion["only_b"] == 1


@pytest.mark.parametrize(
    ("pairs_a", "pairs_b", "message"),
    [
        (PAIRS[:, 0], None, "shape"),
        (np.where(PAIRS == EYE, np.nan, PAIRS), None, "NaN"),
        (PAIRS, PAIRS[:2], "pairs_b has 2 pairs"),
    ],
)
def test_bad_pairs_raise_a_world_error(pairs_a, pairs_b, message: str) -> None:
    with pytest.raises(WorldError, match=message):
        compare_line_of_sight(_world(True, "a"), _world(False, "b"), pairs_a, pairs_b)


def test_subset_wants_one_flag_per_pair() -> None:
    result = compare_line_of_sight(_world(True, "a"), _world(False, "b"), PAIRS)
    with pytest.raises(WorldError, match="mask"):
        result.subset(np.ones(3, dtype=bool))


# ---- pairs ------------------------------------------------------------------------------------


def _lattice_graph(n: int = 12, places: bool = False) -> WaypointGraph:
    """An n x n grid of waypoints 1 m apart, z rising 0.1 m per row (no edges needed here);
    with places, the west half is place 0 ("West") and the east half place 1 ("East")."""
    i, j = np.meshgrid(np.arange(n), np.arange(n), indexing="ij")
    positions = np.column_stack([i.ravel(), j.ravel(), 0.1 * j.ravel()]).astype(np.float64)
    place = np.where(positions[:, 0] < n / 2, 0, 1) if places else np.full(n * n, -1)
    return WaypointGraph(
        positions=positions,
        edge_source=np.zeros(0, np.int32),
        edge_target=np.zeros(0, np.int32),
        edge_kind=np.zeros(0, np.uint8),
        edge_direction=np.zeros(0, np.uint8),
        node_place=place.astype(np.int16),
        place_names=["West", "East"] if places else [],
        regions={},
    )


def test_random_pairs_are_reproducible_with_a_seed_and_differ_between_seeds() -> None:
    graph = _lattice_graph()
    first = random_node_pairs(graph, 500, seed=7, max_distance=5.0)
    again = random_node_pairs(graph, 500, seed=7, max_distance=5.0)
    other = random_node_pairs(graph, 500, seed=8, max_distance=5.0)
    np.testing.assert_array_equal(first, again)
    assert not np.array_equal(first, other)
    assert first.shape == (500, 2) and first.dtype == np.int64


def test_random_pairs_are_distinct_nodes_within_the_distance_band() -> None:
    graph = _lattice_graph()
    nodes = random_node_pairs(graph, 2000, seed=0, max_distance=4.0, min_distance=2.0)
    distance = np.linalg.norm(graph.positions[nodes[:, 0]] - graph.positions[nodes[:, 1]], axis=1)
    assert np.all(nodes[:, 0] != nodes[:, 1])
    assert distance.min() >= 2.0 and distance.max() <= 4.0
    assert len(np.unique(nodes[:, 0])) == graph.num_nodes  # every node gets drawn
    unbounded = random_node_pairs(graph, 2000, seed=0)
    far = np.linalg.norm(
        graph.positions[unbounded[:, 0]] - graph.positions[unbounded[:, 1]], axis=1
    )
    assert far.max() > 10.0


def test_random_pairs_that_cannot_exist_raise_a_graph_error() -> None:
    graph = _lattice_graph()
    with pytest.raises(GraphError, match="found only 0 of 10"):
        random_node_pairs(graph, 10, seed=0, max_distance=0.5)
    with pytest.raises(GraphError, match="no pairs"):
        random_node_pairs(_lattice_graph(1), 10)
    with pytest.raises(GraphError, match="cannot draw"):
        random_node_pairs(graph, -1)


def test_eye_pairs_stand_at_eye_height_over_the_waypoints() -> None:
    graph = _lattice_graph()
    nodes = np.array([[0, 5], [13, 140]])
    eyes = eye_pairs(graph, nodes)
    assert eyes.shape == (2, 2, 3)
    np.testing.assert_allclose(eyes[..., :2], graph.positions[nodes][..., :2])
    np.testing.assert_allclose(eyes[..., 2], graph.positions[nodes][..., 2] + EYE_HEIGHT_M)
    with pytest.raises(GraphError, match="outside"):
        eye_pairs(graph, np.array([[0, graph.num_nodes]]))


def test_sideways_moves_pairs_to_their_left_by_the_distance() -> None:
    pairs = np.array([[(0.0, 0.0, 1.0), (4.0, 0.0, 1.0)], [(1.0, 1.0, 0.0), (1.0, 1.0, 2.0)]])
    moved = sideways(pairs, 0.3)
    np.testing.assert_allclose(moved[0], [(0.0, 0.3, 1.0), (4.0, 0.3, 1.0)])
    np.testing.assert_allclose(moved[1], pairs[1])  # a vertical pair has no sideways
    np.testing.assert_allclose(sideways(pairs, -0.3)[0, :, 1], [-0.3, -0.3])


# ---- placement --------------------------------------------------------------------------------


def test_placement_finds_buried_and_floating_feet() -> None:
    world = World(
        np.concatenate(
            [
                floor(0.0, 0.0, 10.0, 4.0),
                quad((2.0, 0.0, 0.8), (4.0, 0.0, 0.8), (4.0, 4.0, 0.8), (2.0, 4.0, 0.8)),  # mound
                box(6.0, 0.0, 8.0, 4.0, 0.0, 0.2),  # below the step height
            ]
        ),
        name="placement",
        source="hand-made placement",
    )
    feet = np.array(
        [
            (1.0, 2.0, 0.0),  # on the floor
            (3.0, 2.0, 0.0),  # under the 0.8 m sheet
            (7.0, 2.0, 0.0),  # in the 0.2 m box: a step, still standing
            (1.0, 2.0, 0.4),  # 0.4 m above the floor: within the tolerance
            (1.0, 2.0, 0.8),  # 0.8 m above the floor
            (11.0, 2.0, 0.0),  # beyond the floor's edge
        ]
    )
    placement = check_placement(world, feet)
    assert placement.buried.tolist() == [False, True, False, False, False, False]
    assert placement.floating.tolist() == [False, False, False, False, True, True]
    assert placement.misplaced.tolist() == [False, True, False, False, True, True]
    with pytest.raises(WorldError, match="NaN"):
        check_placement(world, np.array([(np.nan, 0.0, 0.0)]))


def test_builtin_waypoints_stand_properly_in_the_world_they_were_built_on() -> None:
    placement = check_placement(nav_world(), builtin_graph().positions)
    assert not placement.buried.any()
    assert not placement.floating.any()


# ---- where ------------------------------------------------------------------------------------


def _comparison(visible_a: list[bool], visible_b: list[bool]) -> LosComparison:
    pairs = np.zeros((len(visible_a), 2, 3))
    pairs[:, 1, 0] = 5.0
    return LosComparison(pairs, pairs, np.array(visible_a), np.array(visible_b), "a", "b")


def test_disagreement_by_place_counts_pairs_for_both_endpoint_places() -> None:
    graph = _lattice_graph(places=True)  # nodes 0..71 west, 72..143 east
    nodes = np.array([[0, 1], [0, 100], [100, 101], [100, 140]])
    comparison = _comparison([True, True, False, True], [True, False, True, True])
    rows = {row.place: row for row in disagreement_by_place(comparison, nodes, graph)}
    assert set(rows) == {"West", "East"}
    assert (rows["West"].pairs, rows["West"].disagree) == (2, 1)
    assert (rows["West"].only_a, rows["West"].only_b) == (1, 0)
    assert (rows["East"].pairs, rows["East"].disagree) == (3, 2)
    assert (rows["East"].only_a, rows["East"].only_b) == (1, 1)
    assert rows["East"].share == pytest.approx(2 / 3)
    with pytest.raises(GraphError, match="3 node pairs for 4"):
        disagreement_by_place(comparison, nodes[:3], graph)


def test_the_plot_is_written_as_a_png(tmp_path: Path) -> None:
    comparison = _comparison([True, False, True], [False, True, True])
    out = tmp_path / "sub" / "los.png"
    plot_los_comparison(comparison, out)
    assert out.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert [p.name for p in out.parent.iterdir()] == ["los.png"]
    with pytest.raises(OutputError):
        plot_los_comparison(comparison, tmp_path)


# ---- real de_dust2 ----------------------------------------------------------------------------


def test_nav_world_and_moh_mesh_mostly_agree_on_line_of_sight() -> None:
    if not MOH_TRI.is_file():
        pytest.skip(f"real de_dust2 mesh not found at {MOH_TRI} (shared data absent)")
    graph = builtin_graph()
    nodes = random_node_pairs(graph, 2000, seed=0, max_distance=40.0)
    with PhysicsWorld(read_mesh(MOH_TRI)) as moh:
        comparison = compare_line_of_sight(nav_world(), moh, eye_pairs(graph, nodes))
        placement = check_placement(moh, graph.positions)
    clean = ~placement.misplaced[nodes].any(axis=1)
    # measured with 20,000 pairs: 91.8% overall, 93.7% without misplaced endpoints
    assert 0.88 <= comparison.agreement <= 0.96
    assert 0.90 <= comparison.subset(clean).agreement <= 0.97
    # the sand mounds (T spawn, Long A) bury some built-in waypoints (measured: about 690)
    assert 300 <= placement.buried.sum() <= 1200
