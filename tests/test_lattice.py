"""The lattice builder on hand-made worlds: counts, directions, edge kinds, connectivity, manual
waypoints and determinism (tests/worlds.py describes each world)."""

from __future__ import annotations

from collections import Counter
from functools import cache

import numpy as np
import pytest
from scipy.sparse import csr_matrix
from scipy.sparse.csgraph import connected_components
from worlds import (
    ALCOVE,
    ALCOVE_POINT,
    BOX,
    BOX_Z,
    DECK,
    DECK_Z,
    GAP_WALL_X,
    LEDGE_X,
    LEDGE_Z,
    alcove_room,
    box,
    floor,
    gap_wall_world,
    jump_box_world,
    ledge_world,
    make_world,
    overpass_world,
    room,
    seeds_of,
    walls_around,
)

from decoy_cli.csgo import HAMMER_TO_M, JUMP_HEIGHT_M, MAP_NAMES
from decoy_cli.errors import GraphError
from decoy_cli.waypoints.build import build_graph, builtin_graph
from decoy_cli.waypoints.graph import EdgeKind, WaypointGraph
from decoy_cli.waypoints.lattice import LatticeParams, LatticeResult, build_lattice
from decoy_cli.world.navmesh import load_navmesh
from decoy_cli.world.physics import PhysicsWorld

WORLDS = {
    "room": room,
    "ledge": ledge_world,
    "jump box": jump_box_world,
    "overpass": overpass_world,
    "gap 0.8": lambda: gap_wall_world(0.8),
    "gap 0.3": lambda: gap_wall_world(0.3),
    "alcove": alcove_room,
}


@cache
def lattice(name: str) -> LatticeResult:
    """The lattice of a hand-made world from its seed (built once per test process)."""
    world = WORLDS[name]()
    with PhysicsWorld(world) as physics:
        return build_lattice(physics, seeds_of(world))


def edge_delta(result: LatticeResult) -> np.ndarray:
    return result.positions[result.edge_target] - result.positions[result.edge_source]


# ---- every world -------------------------------------------------------------------------------


@pytest.mark.parametrize("name", list(WORLDS))
def test_edge_direction_matches_geometry(name: str) -> None:
    """N = +y, E = +x: the edge's horizontal heading lies in its direction's 45-degree sector."""
    result = lattice(name)
    delta = edge_delta(result)
    heading = np.degrees(np.arctan2(delta[:, 0], delta[:, 1])) % 360  # clockwise from north
    deviation = np.abs((heading - 45.0 * result.edge_direction + 180) % 360 - 180)
    assert result.edge_direction.max() <= 7
    assert deviation.max() < 22.5


@pytest.mark.parametrize("name", list(WORLDS))
def test_one_edge_per_direction_and_no_loops(name: str) -> None:
    result = lattice(name)
    slots = Counter(zip(result.edge_source.tolist(), result.edge_direction.tolist(), strict=True))
    assert max(slots.values()) == 1
    pairs = Counter(zip(result.edge_source.tolist(), result.edge_target.tolist(), strict=True))
    assert max(pairs.values()) == 1
    assert not np.any(result.edge_source == result.edge_target)


@pytest.mark.parametrize("name", list(WORLDS))
def test_strongly_connected_after_pruning(name: str) -> None:
    result = lattice(name)
    n = len(result.positions)
    matrix = csr_matrix(
        (np.ones(len(result.edge_source)), (result.edge_source, result.edge_target)), shape=(n, n)
    )
    count, _ = connected_components(matrix, directed=True, connection="strong")
    assert count == 1
    assert result.stats.components_after == 1
    assert result.stats.nodes == n
    assert len(result.pruned_positions) == result.stats.pruned_nodes


@pytest.mark.parametrize("name", list(WORLDS))
def test_drop_edges_are_one_way_and_go_down(name: str) -> None:
    """A drop's reverse is never walked or dropped: at most a jump climbs back (the box)."""
    result = lattice(name)
    kind = result.edge_kind
    by_pair = {
        (u, v): k
        for u, v, k in zip(
            result.edge_source.tolist(), result.edge_target.tolist(), kind.tolist(), strict=True
        )
    }
    drops = np.nonzero(kind == EdgeKind.DROP)[0]
    for e in drops:
        back = by_pair.get((int(result.edge_target[e]), int(result.edge_source[e])))
        assert back in (None, EdgeKind.JUMP)
    # a drop ends lower; by more than a step except where the move first climbs a ramp and
    # then falls off its side (the overpass): the profile, not the end heights, makes a drop
    assert np.all(edge_delta(result)[drops, 2] < 0)
    # walk edges are no steeper than a floor (normal z >= 0.7, about 45.6 degrees; a ramp edge
    # may rise more than the step height); jumps rise, at most a crouch-jump, and by less than
    # a step where the move jumps onto a ramp's side and walks down it
    delta = edge_delta(result)
    dz = delta[:, 2]
    walk = kind == EdgeKind.WALK
    max_slope = np.tan(np.arccos(LatticeParams().min_floor_normal_z))
    assert np.all(np.abs(dz[walk]) <= max_slope * np.linalg.norm(delta[walk, :2], axis=1))
    assert np.all(dz[kind == EdgeKind.JUMP] <= JUMP_HEIGHT_M + 1e-9)
    assert np.all(dz[kind == EdgeKind.JUMP] > 0)


# ---- the room ----------------------------------------------------------------------------------


def test_room_is_a_full_7_by_7_lattice() -> None:
    """A 5 x 5 m room seeded at its centre: lattice lines at 2.5 +- 0.7 k for k <= 3 all lie
    0.4 m or more from the walls (wider than the agent radius), the next ones outside."""
    result = lattice("room")
    assert len(result.positions) == 49
    xs = np.unique(np.round(result.positions[:, 0], 6))
    np.testing.assert_allclose(xs, 2.5 + 0.7 * np.arange(-3, 4), atol=1e-9)
    np.testing.assert_allclose(result.positions[:, 2], 0.0, atol=1e-6)
    # the full 8-neighbourhood grid, both ways: 2 (2 * 7 * 6) straight + 2 (2 * 6 * 6) diagonal
    assert len(result.edge_source) == 312
    assert set(result.edge_kind.tolist()) == {EdgeKind.WALK}
    assert result.stats.nudged_nodes == 0
    np.testing.assert_allclose(np.linalg.norm(edge_delta(result), axis=1).min(), 0.7)


def test_spacing_changes_the_node_count() -> None:
    world = room()
    params = LatticeParams(spacing=1.0, wall_nodes=False)
    with PhysicsWorld(world) as physics:
        result = build_lattice(physics, seeds_of(world), params)
    # lines at 2.5 +- k for k <= 2 (0.5 .. 4.5 m)
    assert len(result.positions) == 25


def test_wall_nodes_stand_where_players_hug_the_walls() -> None:
    """In a 5 m room with 1 m spacing the lattice lines are 0.5 m from the walls; a wall node
    goes toward each wall as far as the capsule allows (wall - radius - 3 cm), linked both ways
    to its parent and along the wall to its neighbours, never two edges in one direction."""
    world = room()
    params = LatticeParams(spacing=1.0)
    with PhysicsWorld(world) as physics:
        result = build_lattice(physics, seeds_of(world), params)
    assert result.stats.wall_nodes == 20
    assert len(result.positions) == 25 + 20
    near = params.agent_radius + 0.03
    xy = result.positions[:, :2]
    on_wall = np.any(np.isclose(xy, near) | np.isclose(xy, 5.0 - near), axis=1)
    assert on_wall.sum() == 20
    walls = np.flatnonzero(on_wall)
    degree = Counter(result.edge_source.tolist())
    for node in walls:
        # back to the parent, plus one or two along the wall (the corner ones have one)
        assert degree[node] in (2, 3)
    pairs = list(zip(result.edge_source.tolist(), result.edge_direction.tolist(), strict=True))
    assert len(pairs) == len(set(pairs))
    # every edge has its reverse, and the whole graph is one strongly connected component
    edges = set(zip(result.edge_source.tolist(), result.edge_target.tolist(), strict=True))
    assert all((v, u) in edges for u, v in edges)
    assert result.stats.components_before == 1


# ---- ledge, box, overpass, gap -----------------------------------------------------------------


def test_ledge_drops_one_way_and_never_climbs() -> None:
    result = lattice("ledge")
    src, dst = result.edge_source, result.edge_target
    pos = result.positions
    lower = (pos[:, 2] < 0.05) & (pos[:, 0] < LEDGE_X) & (pos[:, 1] < 4.0)
    platform = np.abs(pos[:, 2] - LEDGE_Z) < 0.05
    assert lower.sum() > 30 and platform.sum() > 30
    up = lower[src] & platform[dst]
    assert not up.any()
    down = platform[src] & lower[dst]
    assert down.sum() >= 5
    assert np.all(result.edge_kind[down] == EdgeKind.DROP)
    # every drop goes west off the face: W, SW or NW
    assert set(result.edge_direction[down].tolist()) <= {5, 6, 7}
    pairs = set(zip(src.tolist(), dst.tolist(), strict=True))
    assert not any(
        (v, u) in pairs for u, v in zip(src[down].tolist(), dst[down].tolist(), strict=True)
    )
    # the ramp lane keeps both floors in one strongly connected component
    assert result.stats.largest_component_share == 1.0
    ramp = (pos[:, 2] > 0.05) & (pos[:, 2] < LEDGE_Z - 0.02)
    assert ramp.sum() >= 6


def test_box_is_jumped_onto_and_dropped_off() -> None:
    result = lattice("jump box")
    pos, kind, direction = result.positions, result.edge_kind, result.edge_direction
    x0, y0, x1, y1 = BOX
    top = np.abs(pos[:, 2] - BOX_Z) < 0.02
    inside = (pos[:, 0] > x0) & (pos[:, 0] < x1) & (pos[:, 1] > y0) & (pos[:, 1] < y1)
    assert np.array_equal(top, inside)
    # lattice lines 3.3 and 4.0 (seed 0.5 + 0.7 k) cross the box; the four nodes on line 4.0
    # also get a wall node 0.35 m toward the edge 0.5 m away (a cliff edge on the box top)
    lattice_top = top & np.all(np.isclose(pos[:, :2] % 0.7, 0.5), axis=1)
    assert lattice_top.sum() == 4 and top.sum() == 8
    src, dst = result.edge_source, result.edge_target
    onto = ~top[src] & top[dst]
    off = top[src] & ~top[dst]
    assert onto.sum() == off.sum() == 20  # each top lattice node has 5 floor neighbours
    assert np.all(lattice_top[dst[onto]])
    assert np.all(kind[onto] == EdgeKind.JUMP)
    assert np.all(kind[off] == EdgeKind.DROP)
    assert np.all(kind[~onto & ~off] == EdgeKind.WALK)
    # the floor nodes that jump on are the ones the drops land on; a drop the edge wall node
    # took over from its lattice parent keeps the parent's direction
    assert set(src[onto].tolist()) == set(dst[off].tolist())
    from_wall = off & ~lattice_top[src]
    assert from_wall.sum() > 0
    for e in np.flatnonzero(from_wall):
        parent = (dst == src[e]) & lattice_top[src] & (direction == direction[e])
        assert parent.sum() == 1


def crate_room(height_u: float) -> LatticeResult:
    """The jump-box room with the box `height_u` Hammer units high."""
    world = make_world(
        [
            floor(0.0, 0.0, 8.0, 8.0),
            walls_around(0.0, 0.0, 8.0, 8.0),
            box(*BOX, 0.0, height_u * HAMMER_TO_M),
        ],
        "crate",
        (0.5, 0.5, 0.0),
    )
    with PhysicsWorld(world) as physics:
        return build_lattice(physics, seeds_of(world))


@pytest.mark.parametrize(
    ("height_u", "climbed"), [(64.0, True), (65.0, True), (66.0, False), (67.0, False)]
)
def test_a_crouch_jump_gets_onto_a_64_unit_crate_and_no_higher_than_65(
    height_u: float, climbed: bool
) -> None:
    """CS:GO maps build crates 64 u high because a crouch-jump gets onto them (65 u at most)."""
    result = crate_room(height_u)
    top = np.abs(result.positions[:, 2] - height_u * HAMMER_TO_M) < 0.02
    onto = ~top[result.edge_source] & top[result.edge_target]
    assert bool(onto.any()) is climbed
    assert np.all(result.edge_kind[onto] == EdgeKind.JUMP)


BY_THE_LEDGE = (5.0, 1.2, LEDGE_X, 2.9)
"""A box against the ledge face of `ledge_world` (x0, y0, x1, y1), BOX_Z high: the platform is
out of a jump's reach from the floor but not from the box."""


def test_a_box_by_a_ledge_is_the_way_up() -> None:
    parts = [ledge_world().triangles, box(*BY_THE_LEDGE, 0.0, BOX_Z)]
    world = make_world(parts, "box by the ledge", (1.0, 1.0, 0.0))
    graph, _ = build_graph(world, seeds=seeds_of(world))  # verified by the capsule like all
    pos, kind = graph.positions, graph.edge_kind
    x0, y0, x1, y1 = BY_THE_LEDGE
    on_box = (np.abs(pos[:, 2] - BOX_Z) < 0.02) & (pos[:, 0] > x0) & (pos[:, 1] > y0)
    on_box &= (pos[:, 0] < x1) & (pos[:, 1] < y1)
    platform = np.abs(pos[:, 2] - LEDGE_Z) < 0.02
    floor_ = pos[:, 2] < 0.02
    src, dst = graph.edge_source, graph.edge_target
    box_up = on_box[src] & platform[dst]
    assert box_up.any() and np.all(kind[box_up] == EdgeKind.JUMP)
    assert not (floor_[src] & platform[dst]).any()  # 1.5 m: no jump from the floor
    # from the floor in front of the box to the platform behind it: over the box, not round
    # by the ramp lane
    start, end = graph.nearest(np.array([[4.5, 2.4, 0.0], [6.6, 2.4, LEDGE_Z]]))[0]
    path = graph.shortest_path(int(start), int(end))
    assert on_box[path].any()
    assert len(path) <= 5


def test_wall_node_stands_at_a_box_face_and_the_jump_leaves_from_it() -> None:
    """A floor node 0.7 m from the face of a box it jumps onto gets a wall node against the
    face (players wait there before jumping); the jump then leaves from the wall node, and the
    parent walks to it, so no node has two edges in one direction and the box stays reachable."""
    face_x = 3.2
    world = make_world(
        [
            floor(0.0, 0.0, 8.0, 8.0),
            walls_around(0.0, 0.0, 8.0, 8.0),
            box(face_x, 3.2, 4.8, 4.8, 0.0, BOX_Z),
        ],
        "box face",
        (0.5, 0.5, 0.0),
    )
    params = LatticeParams(spacing=1.0)
    with PhysicsWorld(world) as physics:
        result = build_lattice(physics, seeds_of(world), params)
    pos, src, dst = result.positions, result.edge_source, result.edge_target
    kind, direction = result.edge_kind, result.edge_direction
    on_face = np.isclose(pos[:, 0], face_x - params.agent_radius - 0.03) & (pos[:, 2] < 0.05)
    face_node = int(np.flatnonzero(on_face & np.isclose(pos[:, 1], 3.5))[0])
    parent = int(np.flatnonzero(np.all(np.isclose(pos, (2.5, 3.5, 0.0), atol=0.02), axis=1))[0])
    east = 2
    from_parent = (src == parent) & (direction == east)
    assert dst[from_parent].tolist() == [face_node] and kind[from_parent][0] == EdgeKind.WALK
    from_face = (src == face_node) & (direction == east)
    assert kind[from_face].tolist() == [EdgeKind.JUMP]
    assert np.allclose(pos[dst[from_face][0]], (3.5, 3.5, BOX_Z), atol=0.02)
    pairs = list(zip(src.tolist(), direction.tolist(), strict=True))
    assert len(pairs) == len(set(pairs))
    assert result.stats.components_before == 1


@cache
def overpass_graph() -> WaypointGraph:
    world = overpass_world()
    graph, _ = build_graph(world, seeds=seeds_of(world))
    return graph


def test_overpass_has_both_floors_at_the_same_spots() -> None:
    graph = overpass_graph()
    pos = graph.positions
    x0, y0, x1, y1 = DECK
    under = (pos[:, 0] > x0) & (pos[:, 0] < x1) & (pos[:, 1] > y0) & (pos[:, 1] < y1)
    deck = under & (np.abs(pos[:, 2] - DECK_Z) < 0.02)
    ground = under & (np.abs(pos[:, 2]) < 0.02)
    assert deck.sum() >= 20
    key = lambda rows: {tuple(np.round(p[:2], 6)) for p in rows}  # noqa: E731
    assert key(pos[deck]) == key(pos[ground])


@pytest.mark.parametrize("lift", [0.0, 0.3, 1.0])
def test_overpass_nearest_stays_on_its_floor(lift: float) -> None:
    """A player on the deck (or jumping above it) never snaps to the ground 4 m below, and one
    on the ground under the deck never snaps up."""
    graph = overpass_graph()
    pos = graph.positions
    x0, y0, x1, y1 = DECK
    under = (pos[:, 0] > x0) & (pos[:, 0] < x1) & (pos[:, 1] > y0) & (pos[:, 1] < y1)
    for floor_z in (DECK_Z, 0.0):
        nodes = np.nonzero(under & (np.abs(pos[:, 2] - floor_z) < 0.02))[0]
        queries = pos[nodes] + np.array([0.2, -0.15, lift])
        index, distance = graph.nearest(queries)
        assert np.all(index >= 0)
        np.testing.assert_allclose(pos[index, 2], floor_z, atol=0.02)
        assert np.all(distance < lift + 0.3)


def test_wall_gap_one_agent_wide_connects_both_halves() -> None:
    result = lattice("gap 0.8")
    west = result.positions[:, 0] < GAP_WALL_X
    assert west.sum() > 30 and (~west).sum() > 30
    crossing = west[result.edge_source] != west[result.edge_target]
    assert crossing.sum() >= 2  # both ways through the gap
    assert np.all(np.abs(result.positions[result.edge_source[crossing], 1] - 3.0) < 0.5)


def test_wall_gap_too_narrow_keeps_halves_apart() -> None:
    result = lattice("gap 0.3")
    assert len(result.positions) > 30
    assert np.all(result.positions[:, 0] < GAP_WALL_X)


# ---- manual waypoints, seeds, determinism ------------------------------------------------------


def test_manual_waypoint_in_unreached_alcove_is_linked() -> None:
    world = alcove_room()
    x0, y0, x1, y1 = ALCOVE
    plain = lattice("alcove")
    in_alcove = lambda p: (p[:, 0] > x0) & (p[:, 0] < x1) & (p[:, 1] > y0) & (p[:, 1] < y1)  # noqa: E731
    assert not in_alcove(plain.positions).any()  # the lattice does not get in by itself

    with PhysicsWorld(world) as physics:
        result = build_lattice(physics, seeds_of(world), manual=np.array([ALCOVE_POINT]))
    assert result.stats.manual_added == 1 and result.stats.manual_dropped == 0
    node = np.nonzero(in_alcove(result.positions))[0]
    assert len(node) == 1
    np.testing.assert_allclose(result.positions[node[0]], ALCOVE_POINT, atol=1e-6)
    assert np.any(result.edge_source == node[0]) and np.any(result.edge_target == node[0])
    assert len(result.positions) == len(plain.positions) + 1
    slots = Counter(zip(result.edge_source.tolist(), result.edge_direction.tolist(), strict=True))
    assert max(slots.values()) == 1


def test_manual_waypoint_off_the_world_raises() -> None:
    world = room()
    with PhysicsWorld(world) as physics, pytest.raises(GraphError, match="manual waypoint 1"):
        build_lattice(
            physics, seeds_of(world), manual=np.array([[2.5, 2.5, 0.0], [40.0, 40.0, 0.0]])
        )


def test_manual_waypoint_far_above_the_floor_raises() -> None:
    world = room()
    with PhysicsWorld(world) as physics, pytest.raises(GraphError, match="not on a floor"):
        build_lattice(physics, seeds_of(world), manual=np.array([[2.5, 2.5, 2.0]]))


@pytest.mark.parametrize(
    ("seeds", "message"),
    [(np.zeros((0, 3)), "no seed points"), (np.array([[40.0, 40.0, 0.0]]), "not above a floor")],
)
def test_bad_seeds_raise(seeds: np.ndarray, message: str) -> None:
    with PhysicsWorld(room()) as physics, pytest.raises(GraphError, match=message):
        build_lattice(physics, seeds)


def test_builds_are_deterministic(tmp_path) -> None:
    world = jump_box_world()
    first, _ = build_graph(world, seeds=seeds_of(world))
    second, _ = build_graph(jump_box_world(), seeds=seeds_of(world))
    for name in ("positions", "edge_source", "edge_target", "edge_kind", "edge_direction"):
        np.testing.assert_array_equal(getattr(first, name), getattr(second, name))
    first.save(tmp_path / "a.npz")
    second.save(tmp_path / "b.npz")
    assert (tmp_path / "a.npz").read_bytes() == (tmp_path / "b.npz").read_bytes()
    assert first.meta["world"]["sha256"] == world.fingerprint()
    assert first.meta["seeds_m"] == seeds_of(world).tolist()
    # node order is canonical: sorted by x, then y, then z
    order = np.lexsort(np.round(first.positions, 6).T[::-1])
    np.testing.assert_array_equal(order, np.arange(first.num_nodes))


# ---- the shipped graphs ------------------------------------------------------------------------


@pytest.mark.parametrize("map_name", MAP_NAMES)
def test_shipped_graph_invariants(map_name: str) -> None:
    """The same invariants on every shipped graph (rebuilding them is the CLI test's job). Nudged
    nodes bend some edges: a few dozen lie up to ~31 degrees off their compass direction, none
    by half a sector or more (ladders aside). Each region holds waypoints of its nav places only."""
    graph = builtin_graph(map_name)
    count, _ = connected_components(graph.adjacency, directed=True, connection="strong")
    assert count == 1
    assert graph.num_nodes > 4000 and graph.num_edges > 25_000
    slots = Counter(zip(graph.edge_source.tolist(), graph.edge_direction.tolist(), strict=True))
    assert max(slots.values()) == 1
    # a ladder takes the free direction nearest its climb's, which may be farther off
    along = graph.edge_kind != EdgeKind.LADDER
    delta = graph.positions[graph.edge_target] - graph.positions[graph.edge_source]
    heading = np.degrees(np.arctan2(delta[:, 0], delta[:, 1])) % 360
    deviation = np.abs((heading - 45.0 * graph.edge_direction + 180) % 360 - 180)[along]
    assert deviation.max() < 45.0
    assert np.mean(deviation < 22.5) > 0.998
    for region in ("t_spawn", "ct_spawn", "bombsite_a", "bombsite_b"):
        nodes = graph.region_of(region)
        assert len(nodes) >= 20
        places = {graph.place_names[p] for p in graph.node_place[nodes]}
        assert places <= set(load_navmesh(map_name).regions[region])
    assert np.mean(graph.node_place >= 0) > 0.85  # some nav areas have no place name
