"""Ladders: read from a CS:GO `.nav` file (decoy_cli/world/nav_file.py) and a map's
`nav_ladders.csv`, joined into the lattice (decoy_cli/waypoints/ladders.py) and climbed by the
movers at the climbing speed. The nav files here are written by the tests in the format's
layout; the world is a hand-made tower whose platform only a ladder reaches."""

from __future__ import annotations

import math
import os
import struct
from functools import cache
from pathlib import Path

import numpy as np
import pytest
from test_plans import make_graph
from worlds import floor, graph_of, make_world, seeds_of, wall, walls_around

from decoy_cli.csgo import HAMMER_TO_M, LADDER_SPEED_M_S, SAFE_DROP_M, TICK_RATE
from decoy_cli.errors import WorldError
from decoy_cli.replay import PathCache, snap_positions
from decoy_cli.replay.rounds import plan_player
from decoy_cli.sim.movement import KinematicMover, PhysicsMover, kernels
from decoy_cli.waypoints.build import builtin_graph
from decoy_cli.waypoints.graph import RUN_SPEED_M_S, EdgeKind, WaypointGraph
from decoy_cli.waypoints.ladders import add_ladder_edges
from decoy_cli.waypoints.lattice import LatticeParams, build_lattice
from decoy_cli.world import nav_file
from decoy_cli.world.nav_data import load_navmesh, read_ladders
from decoy_cli.world.nav_file import read_nav_ladders
from decoy_cli.world.physics import PhysicsWorld
from decoy_cli.world.world import World

# ---- the .nav file ------------------------------------------------------------------------------


def nav_area(area_id: int, sub_version: int) -> bytes:
    """One version-16 area with something in every variable-length part."""
    out = struct.pack("<II3f3f2f", area_id, 0, 0, 0, 0, 100, 100, 0, 0, 0)
    out += struct.pack("<I2I", 2, 7, 8) + struct.pack("<I", 0) * 3  # links: two north
    out += struct.pack("<B", 1) + struct.pack("<I3fB", 5, 1, 2, 3, 0)  # a hiding spot
    out += struct.pack("<I", 1) + struct.pack("<IBIB", 7, 0, 8, 2)  # an encounter path...
    out += struct.pack("<B", 2) + struct.pack("<IB", 9, 10) * 2  # ...with two spots
    out += struct.pack("<H", 1)  # place
    out += struct.pack("<I1I", 1, 1) + struct.pack("<I", 0)  # ladder links up, down
    out += struct.pack("<2f4f", 0, 0, 1, 1, 1, 1)  # occupy times, light
    out += struct.pack("<I", 2) + struct.pack("<IB", 7, 1) * 2  # visible areas
    out += struct.pack("<I", 0)  # inherit visibility
    if sub_version == 1:
        out += struct.pack("<B", 1) + struct.pack("<IIBIB", 1, 2, 0, 3, 0)  # approach spot
    return out


LADDERS = [
    (4, 23.0, (10.0, 20.0, 200.0), (10.0, 20.0, 0.0)),
    (9, 12.0, (-5.5, 3.0, 64.0), (-5.5, 3.0, -96.0)),
]


def nav_bytes(sub_version: int = 1, ladders=LADDERS, version: int = 16) -> bytes:
    out = struct.pack("<IIIIB", 0xFEEDFACE, version, sub_version, 123456, 1)
    out += struct.pack("<H", 1) + struct.pack("<H", 7) + b"Ladder\0"  # one place
    out += struct.pack("<B", 0)
    out += struct.pack("<I", 2) + nav_area(1, sub_version) + nav_area(2, sub_version)
    out += struct.pack("<I", len(ladders))
    for ladder_id, width, top, bottom in ladders:
        length = top[2] - bottom[2]
        out += struct.pack("<If3f3ffI5I", ladder_id, width, *top, *bottom, length, 1, 1, 0, 0, 0, 2)
    return out


@pytest.mark.parametrize("sub_version", [0, 1])
def test_the_ladders_of_a_nav_file_are_read_past_its_areas(
    tmp_path: Path, sub_version: int
) -> None:
    path = tmp_path / "map.nav"
    path.write_bytes(nav_bytes(sub_version))
    ladders = read_nav_ladders(path)
    expected = [[i, w, *top, *bottom] for i, w, top, bottom in LADDERS]
    np.testing.assert_allclose(ladders, expected)


@pytest.mark.parametrize(
    ("data", "message"),
    [
        (nav_bytes()[:-30], "2 ladders do not fit"),
        (nav_bytes()[:200], "truncated|runs past the end"),
        (b"\0" * 64, "not a nav file"),
        (nav_bytes(version=9), "nav version 9"),
        (nav_bytes()[:-124] + struct.pack("<I", 10**8), "100000000 ladders do not fit"),
    ],
    ids=["cut in the ladders", "cut in the areas", "no header", "old version", "huge count"],
)
def test_a_bad_nav_file_is_one_error(tmp_path: Path, data: bytes, message: str) -> None:
    path = tmp_path / "bad.nav"
    path.write_bytes(data)
    with pytest.raises(WorldError, match=message):
        read_nav_ladders(path)


def test_a_nav_file_of_another_sub_version_or_with_a_bad_ladder_is_refused(tmp_path: Path) -> None:
    path = tmp_path / "map.nav"
    path.write_bytes(nav_bytes(sub_version=2))
    with pytest.raises(WorldError, match="sub-version 2"):
        read_nav_ladders(path)
    for top_z, message in ((-200.0, "top is not above its bottom"), (math.nan, "NaN")):
        bad = [(4, 23.0, (10.0, 20.0, top_z), (10.0, 20.0, 0.0))]
        path.write_bytes(nav_bytes(ladders=bad))
        with pytest.raises(WorldError, match=message):
            read_nav_ladders(path)


def test_a_nav_path_that_is_no_regular_file_or_too_large_is_refused(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    with pytest.raises(WorldError, match="not a regular file"):
        read_nav_ladders(tmp_path)
    if hasattr(os, "mkfifo"):  # a FIFO would block a reader forever
        os.mkfifo(tmp_path / "fifo.nav")
        with pytest.raises(WorldError, match="not a regular file"):
            read_nav_ladders(tmp_path / "fifo.nav")
    with pytest.raises(WorldError, match="cannot read"):
        read_nav_ladders(tmp_path / "missing.nav")
    path = tmp_path / "map.nav"
    path.write_bytes(nav_bytes())
    monkeypatch.setattr(nav_file, "MAX_NAV_BYTES", 100)
    with pytest.raises(WorldError, match="too large"):
        read_nav_ladders(path)


def test_a_huge_count_in_a_nav_area_is_refused_before_reading(tmp_path: Path) -> None:
    data = bytearray(nav_bytes())
    # the first area's first link count (after the header, one place, the unnamed byte, the
    # area count and the area's 40 bytes of id, flags, corners and heights)
    offset = 17 + 2 + 2 + 7 + 1 + 4 + 40
    assert struct.unpack_from("<I", data, offset)[0] == 2
    struct.pack_into("<I", data, offset, 2**31)
    path = tmp_path / "huge.nav"
    path.write_bytes(bytes(data))
    with pytest.raises(WorldError, match="runs past the end"):
        read_nav_ladders(path)


# ---- a map's nav_ladders.csv --------------------------------------------------------------------


@pytest.mark.parametrize(
    ("row", "message"),
    [
        ("1,23,0,0,100,0,0", "needs numbers"),
        ("1,23,0,0,abc,0,0,0", "needs numbers"),
        ("1,23,0,0,0,0,0,100", "top is not above its bottom"),
        ("1,23,0,0,1e308,0,0,0", "off the map's nav mesh"),
        ("1,23,90000,0,100,90000,0,0", "off the map's nav mesh"),
    ],
)
def test_a_bad_ladder_row_is_one_error_naming_file_and_line(
    tmp_path: Path, row: str, message: str
) -> None:
    path = tmp_path / "nav_ladders.csv"
    path.write_text(
        f"ladder_id,width,top_x,top_y,top_z,bottom_x,bottom_y,bottom_z\n1,23,0,0,9,0,0,1\n{row}\n"
    )
    with pytest.raises(WorldError, match=rf"line 3: .*{message}"):
        read_ladders(path, load_navmesh("de_nuke"))


def test_an_unreadable_ladders_file_is_one_error(tmp_path: Path) -> None:
    path = tmp_path / "nav_ladders.csv"
    path.write_bytes(b"ladder_id,top_x\n\xff\xfe\n")
    with pytest.raises(WorldError, match="not a readable CSV file"):
        read_ladders(path, load_navmesh("de_nuke"))


def test_the_shipped_ladders_are_the_maps_nav_files_and_nuke_has_its_five() -> None:
    assert len(load_navmesh("de_nuke").ladders) == 5
    assert len(load_navmesh("de_train").ladders) == 7
    assert len(load_navmesh("de_dust2").ladders) == 0


# ---- the lattice: a tower only a ladder climbs --------------------------------------------------

PLATFORM_Z = 4.5
"""The platform's height: far above a crouch-jump, and a drop from it does damage (deeper than
`SAFE_DROP_M`), so a player climbs down."""
FACE_X = 4.85
"""The platform's face; the lower floor lies on one side of it (x 0..FACE_X), the platform on the
other (x FACE_X..8), both y 0..4. Walls close the lower room and the platform."""


def tower(mirrored: bool = False) -> World:
    """The tower; `mirrored`: the same, flipped east-west (the platform lies west of the face)."""
    parts = [
        floor(0.0, 0.0, FACE_X, 4.0),
        walls_around(0.0, 0.0, FACE_X, 4.0, PLATFORM_Z),
        floor(FACE_X, 0.0, 8.0, 4.0, PLATFORM_Z),
        wall(8.0, 0.0, 8.0, 4.0, PLATFORM_Z, PLATFORM_Z + 3.0),
        wall(FACE_X, 0.0, 8.0, 0.0, PLATFORM_Z, PLATFORM_Z + 3.0),
        wall(FACE_X, 4.0, 8.0, 4.0, PLATFORM_Z, PLATFORM_Z + 3.0),
    ]
    triangles = np.concatenate(parts)
    if mirrored:
        triangles = (triangles * np.array([-1.0, 1.0, 1.0]))[:, ::-1]  # keep the winding
    seed = (-1.0 if mirrored else 1.0, 1.0, 0.0)
    return make_world([triangles], "tower", seed)


def ladder_u(
    top_above: float = 0.05,
    bottom_above: float = 0.05,
    off_face: float = 0.1,
    mirrored: bool = False,
) -> np.ndarray:
    """A ladder on the face (Hammer units): its top `top_above` the platform, its bottom
    `bottom_above` the floor, `off_face` metres in front of the face on the floor's side."""
    x = (FACE_X - off_face) * (-1.0 if mirrored else 1.0)
    ends = [x, 2.0, PLATFORM_Z + top_above, x, 2.0, bottom_above]
    return np.array([ends]) / HAMMER_TO_M


def build(ladders: np.ndarray | None, mirrored: bool = False) -> WaypointGraph:
    world = tower(mirrored)
    with PhysicsWorld(world) as physics:
        return graph_of(build_lattice(physics, seeds_of(world), ladders_u=ladders))


@cache
def tower_graph(mirrored: bool = False) -> WaypointGraph:
    return build(ladder_u(mirrored=mirrored), mirrored)


def on_platform(graph: WaypointGraph) -> np.ndarray:
    return np.abs(graph.positions[:, 2] - PLATFORM_Z) < 0.05


def ladder_edges(graph: WaypointGraph) -> tuple[int, int]:
    """The (up, down) ladder edges of a graph with one ladder."""
    ladder = np.flatnonzero(graph.edge_kind == EdgeKind.LADDER)
    assert len(ladder) == 2
    up, down = sorted(ladder.tolist(), key=lambda e: graph.positions[graph.edge_target[e], 2])[::-1]
    return up, down


def test_without_the_ladder_the_platform_has_no_waypoint() -> None:
    graph = build(None)
    assert not on_platform(graph).any()
    assert not (graph.edge_kind == EdgeKind.LADDER).any()


@pytest.mark.parametrize("mirrored", [False, True], ids=["platform east", "platform west"])
def test_the_ladder_joins_the_platform_both_ways(mirrored: bool) -> None:
    graph = tower_graph(mirrored)
    top = on_platform(graph)
    assert top.sum() >= 15  # the platform is flooded from the ladder's seed
    up, down = ladder_edges(graph)
    assert top[graph.edge_target[up]] and not top[graph.edge_source[up]]
    assert graph.edge_source[down] == graph.edge_target[up]
    assert graph.edge_target[down] == graph.edge_source[up]
    # the climb's compass direction: towards the platform (E = 2, W = 6), down the other way
    assert graph.edge_direction[up] == (6 if mirrored else 2)
    assert graph.edge_direction[down] in ((1, 2, 3) if mirrored else (5, 6, 7))
    # each end within reach of the ladder, on its floor
    ladder = ladder_u(mirrored=mirrored)[0] * HAMMER_TO_M
    assert np.hypot(*(graph.positions[graph.edge_source[up], :2] - ladder[3:5])) <= 1.4
    assert np.hypot(*(graph.positions[graph.edge_target[up], :2] - ladder[:2])) <= 1.4
    # one edge per direction and per pair still, and the platform is strongly connected
    pairs = set(zip(graph.edge_source.tolist(), graph.edge_direction.tolist(), strict=True))
    assert len(pairs) == graph.num_edges
    joined = set(zip(graph.edge_source.tolist(), graph.edge_target.tolist(), strict=True))
    assert len(joined) == graph.num_edges
    stats = graph.meta["stats"]
    assert (stats["ladders"], stats["ladders_joined"], stats["edges"]["ladder"]) == (1, 1, 2)
    assert np.all(np.isfinite(graph.path_lengths(int(graph.edge_source[up]))))


def test_a_climb_costs_the_run_it_could_have_made_in_its_time() -> None:
    graph = tower_graph()
    e = int(np.flatnonzero(graph.edge_kind == EdgeKind.LADDER)[0])
    assert graph.edge_cost[e] == pytest.approx(
        graph.edge_length[e] * RUN_SPEED_M_S / LADDER_SPEED_M_S
    )
    assert graph.edge_cost[e] > 1.5 * graph.edge_length[e]


@pytest.mark.parametrize(
    ("ladder", "joined"),
    [
        (ladder_u(top_above=1.0), True),  # the brush rises a metre past the lip
        (ladder_u(top_above=1.5), False),  # more than a crouch-jump: no floor at its top
        (ladder_u(top_above=-0.5), False),  # its top half a metre under the lip
        (ladder_u(bottom_above=0.8), True),
        (ladder_u(bottom_above=1.0), False),
        (ladder_u(off_face=2.0), False),  # two metres from the face: it leads nowhere
    ],
    ids=["top 1 m up", "top 1.5 m up", "top under the lip", "foot 0.8 m up", "foot 1 m up", "far"],
)
def test_a_ladder_joins_the_floors_within_its_bands_and_reach(
    ladder: np.ndarray, joined: bool
) -> None:
    graph = build(ladder)
    assert graph.meta["stats"]["ladders_joined"] == int(joined)
    assert (graph.edge_kind == EdgeKind.LADDER).any() == joined


# ---- joining nodes: one edge per direction and per pair -----------------------------------------

FOOT, TOP_A, TOP_B = 0, 1, 2
POSITIONS = np.array([[0.0, 0.0, 0.0], [0.6, 0.0, 3.0], [0.6, 0.1, 3.0], [-0.7, 0.0, 0.0]])
"""A foot, two tops east of it (for a ladder each, both climbs heading east), and a floor node
west of the foot."""


def joined_edges(ladders_m: list[list[float]], edges: list[tuple[int, int, int, int]]):
    ladders_u = np.asarray(ladders_m) / HAMMER_TO_M
    return add_ladder_edges(POSITIONS, np.array(edges).reshape(-1, 4), ladders_u, LatticeParams())


def test_two_ladders_from_one_foot_take_two_directions() -> None:
    edges, joined = joined_edges(
        [[0.6, 0.0, 3.0, 0.0, 0.0, 0.0], [0.6, 0.1, 3.0, 0.0, 0.0, 0.0]], [(FOOT, 3, 0, 6)]
    )
    assert joined == 2
    up = edges[(edges[:, 0] == FOOT) & (edges[:, 2] == EdgeKind.LADDER)]
    assert sorted(up[:, 1].tolist()) == [TOP_A, TOP_B]
    assert sorted(up[:, 3].tolist()) == [2, 3]  # east, then the next free one (south-east)


def test_a_ladder_whose_ends_find_one_node_joins_nothing() -> None:
    edges, joined = joined_edges([[0.0, 0.0, 0.3, 0.0, 0.0, 0.0]], [])  # a step, not a climb
    assert joined == 0 and len(edges) == 0


def test_a_second_ladder_between_the_same_nodes_adds_nothing() -> None:
    edges, joined = joined_edges(
        [[0.6, 0.0, 3.0, 0.0, 0.0, 0.0], [0.6, 0.02, 3.0, 0.0, 0.02, 0.0]], []
    )
    assert joined == 2 and len(edges) == 2


@pytest.mark.parametrize(("depth", "kind"), [(3.0, EdgeKind.DROP), (5.0, EdgeKind.LADDER)])
def test_a_drop_beside_the_ladder_stays_unless_it_hurts(depth: float, kind: EdgeKind) -> None:
    assert 3.0 < SAFE_DROP_M < 5.0
    positions = POSITIONS.copy()
    positions[TOP_A, 2] = depth
    ladders_u = np.array([[0.6, 0.0, depth, 0.0, 0.0, 0.0]]) / HAMMER_TO_M
    drop = np.array([[TOP_A, FOOT, int(EdgeKind.DROP), 6]])
    edges, joined = add_ladder_edges(positions, drop, ladders_u, LatticeParams())
    assert joined == 1
    down = edges[(edges[:, 0] == TOP_A) & (edges[:, 1] == FOOT)]
    assert len(down) == 1 and down[0, 2] == kind and down[0, 3] == 6


# ---- the movers climb at the climbing speed ----------------------------------------------------


def test_the_kernels_ladder_constant_is_the_graphs() -> None:
    assert kernels.LADDER_EDGE == EdgeKind.LADDER


@pytest.mark.parametrize("mover_kind", ["kinematic", "physics"])
def test_an_agent_climbs_at_the_climbing_speed_whatever_it_runs(mover_kind: str) -> None:
    graph = tower_graph()
    up = int(
        next(
            e
            for e in np.flatnonzero(graph.edge_kind == EdgeKind.LADDER)
            if graph.positions[graph.edge_target[e], 2] > 1.0
        )
    )
    start, end = graph.positions[graph.edge_source[up]], graph.positions[graph.edge_target[up]]
    with PhysicsWorld(tower()) as physics:
        mover = KinematicMover() if mover_kind == "kinematic" else PhysicsMover(physics)
        mover.reset(start[None, :])
        mover.set_goal(0, end, EdgeKind.LADDER, 6.0)  # a knife runs at 4.76 m/s
        heights = []
        tick = 0
        while tick < 10 * TICK_RATE:
            tick += 1
            step = mover.step()
            heights.append(mover.positions[0, 2])
            if step.arrived[0]:
                break
        if mover_kind == "physics":
            mover.close()
    expected = math.ceil(graph.edge_length[up] / LADDER_SPEED_M_S * TICK_RATE - 1e-6)
    assert abs(tick - expected) <= 1
    np.testing.assert_allclose(mover.positions[0], end, atol=1e-9)
    assert np.all(np.diff(heights) > 0)  # a steady climb, no jump


@pytest.mark.parametrize(
    ("max_speed", "asked", "climb"),
    [(150 * HAMMER_TO_M, 150 * HAMMER_TO_M, LADDER_SPEED_M_S), (4.76, 1.5, 1.5)],
    ids=["a Negev at full speed", "asked to go slow"],
)
def test_the_climbing_speed_is_no_weapons_and_a_slower_climb_is_asked_for(
    max_speed: float, asked: float, climb: float
) -> None:
    graph = tower_graph()
    up, _ = ladder_edges(graph)
    start, end = graph.positions[graph.edge_source[up]], graph.positions[graph.edge_target[up]]
    mover = KinematicMover()
    mover.reset(start[None, :], max_speed=max_speed)
    mover.set_goal(0, end, EdgeKind.LADDER, asked)
    ticks = next(t for t in range(1, 20 * TICK_RATE) if mover.step().arrived[0])
    assert abs(ticks - graph.edge_length[up] / climb * TICK_RATE) <= 1


def test_the_shipped_nuke_graph_climbs_to_heaven_and_the_roof() -> None:
    graph = builtin_graph("de_nuke")
    ladder = graph.edge_kind == EdgeKind.LADDER
    assert ladder.sum() >= 8
    places = graph.place_names
    reached = {places[p] for p in graph.node_place[graph.edge_target[ladder]] if p >= 0}
    assert {"Heaven", "Roof"} <= reached


@pytest.mark.parametrize(
    ("nodes", "seconds"),
    [
        ((0, 6), 1.5),  # a walk then the climb, tight: the walk needs 4.45 m/s
        ((0, 6), 3.0),  # the same with time to spare
        ((6, 0), 2.0),  # down the ladder first, then the walk
        ((5, 6), 2.0),  # the ladder alone, slowly: on time, not early
    ],
    ids=["tight", "slack", "down first", "ladder alone"],
)
def test_a_replay_over_a_ladder_reaches_its_target_on_time(
    nodes: tuple[int, int], seconds: float
) -> None:
    """The plan gives the climb its time at the climbing speed and the walk the rest (timed as
    running, the tight case arrived late: the capped climb took longer than planned)."""
    from test_plans import at, plan_for, with_ladder

    from decoy_cli.csgo import tick_at
    from decoy_cli.replay.policy import PlanPolicy
    from decoy_cli.sim.engine import Simulator
    from decoy_cli.sim.rules import BombRules, RulesConfig
    from decoy_cli.sim.sites import SiteZones
    from decoy_cli.sim.state import Agents

    graph = with_ladder()
    times = [0.0, seconds, seconds + 1.0]
    plans = [
        plan_for(graph, at(nodes[0], nodes[1], nodes[1], graph=graph), seconds=times),
        plan_for(graph, at(11, 11, 11, graph=graph), seconds=times),  # a CT stands
    ]
    assert not plans[0].interval_infeasible[0]
    start = np.array([nodes[0], 11])
    agents = Agents.create(["t", "ct"], ["T", "CT"], graph.positions[start], start)
    policy = PlanPolicy(plans, tick_at, graph)
    zones = SiteZones(nodes={"A": [[100.0, 100.0, 0.0]]})  # nobody can plant
    sim = Simulator(graph, agents, KinematicMover(), policy, BombRules(zones, RulesConfig()))
    sim.run(to_tick=tick_at(seconds + 0.5))
    log = policy.logs[0]
    assert log.arrival_tick[1] >= 0
    assert abs(log.arrival_tick[1] - log.deadline_tick[1]) <= 1


def test_the_cap_leaves_the_climb_out_of_the_players_pace() -> None:
    """The speed cap is the player's pace over the running time: its straight line less the
    ladder (climbed in the climb's time), not the whole of it."""
    from test_plans import at, plan_for, with_ladder

    from decoy_cli.replay.rounds import MAX_ZIGZAG, interval_caps

    graph = with_ladder()
    positions = at(0, 6, graph=graph)
    plan = plan_for(graph, positions, seconds=[0.0, 1.5])
    climbed = plan.interval_length_m[0] - plan.interval_run_m[0]
    assert climbed == pytest.approx(math.hypot(0.7, 2.0))
    straight = np.linalg.norm(positions[1] - positions[0]) - climbed
    pace = straight / plan.interval_running_s[0]
    zigzag = min(plan.interval_run_m[0] / straight, MAX_ZIGZAG)
    expected = max(plan.interval_max_speed_m_s[0], pace) * zigzag
    assert interval_caps(plan, positions)[0] == pytest.approx(expected)


def test_random_play_over_a_ladder_is_the_same_compiled_and_stepped() -> None:
    """The compiled quiet stretches (`quiet_play`) climb as stepping every tick does."""
    from busy_rounds import random_round

    graph = tower_graph()
    up, _ = ladder_edges(graph)
    foot = graph.positions[graph.edge_source[up]]
    near = np.argsort(np.linalg.norm(graph.positions - foot, axis=1))[:8]
    climbed = 0
    for seed in range(3):
        stepped = random_round(graph, near, seed, compiled=False, ticks=2000, every=7)
        compiled = random_round(graph, near, seed, compiled=True, ticks=2000, every=7)
        assert compiled.events == stepped.events, seed
        np.testing.assert_array_equal(compiled.recording.position, stepped.recording.position)
        heights = stepped.recording.position[:, :, 2]
        climbed += int(((heights > 1.0) & (heights < PLATFORM_Z - 1.0)).any(axis=0).sum())
    assert climbed >= 3  # agents were seen on the ladder


# ---- the replay follows a climb -------------------------------------------------------------


def ladder_and_drop() -> WaypointGraph:
    """A ledge (0, 1 at z = 3) over a floor (2, 3 at z = 0): a ladder from the foot 3 up to 0 and
    down again, and a drop from 1 to 2 with a walk 2 -> 3, quicker down than the climb."""
    positions = [(0.0, 0.0, 3.0), (0.7, 0.0, 3.0), (0.7, 0.7, 0.0), (0.0, 0.7, 0.0)]
    edges = [
        (0, 1, EdgeKind.WALK, 2),
        (1, 0, EdgeKind.WALK, 6),
        (1, 2, EdgeKind.DROP, 0),
        (2, 3, EdgeKind.WALK, 6),
        (3, 2, EdgeKind.WALK, 2),
        (3, 0, EdgeKind.LADDER, 4),
        (0, 3, EdgeKind.LADDER, 0),
    ]
    return make_graph(positions, edges)


def test_a_point_is_on_a_ladder_between_its_ends_heights_and_within_reach() -> None:
    graph = ladder_and_drop()
    points = np.array(
        [
            [0.0, 0.35, 2.0],  # on the ladder
            [0.0, 0.35, 1.0],
            [0.5, 0.35, 1.0],  # 0.5 m across: still within reach
            [1.0, 0.35, 1.0],  # 1 m across: beside it, not on it
            [0.0, 0.35, 3.5],  # above the top
        ]
    )
    up = int(np.flatnonzero((graph.edge_source == 3) & (graph.edge_target == 0))[0])
    assert graph.ladders.tolist() == [up]  # one edge per ladder: the one from its foot
    assert graph.on_ladders(points)[:, 0].tolist() == [True, True, True, False, False]


def test_a_ladder_passage_targets_the_end_left_and_the_end_reached_at_the_climbing_speed() -> None:
    """Down the ladder of `ladder_and_drop`, frames 0.5 s apart: on the ledge (node 0), 0.1 m
    below its floor on the ladder (snapped to node 0, but climbing), half way with no floor
    found, 0.2 m above the foot (snapped to node 3, still climbing), at the foot. The passage
    targets node 0 when he left it and node 3 when he reached it, by the climbing speed; the
    path between is the ladder though the drop beside it is quicker."""
    graph = ladder_and_drop()
    positions = np.array(
        [[0.0, 0.0, 3.0], [0.0, 0.05, 2.9], [0.0, 0.35, 1.5], [0.0, 0.6, 0.2], [0.0, 0.7, 0.0]]
    )
    floor = np.array([3.0, 3.0, np.nan, 0.0, 0.0])
    alive = np.ones(5, bool)
    snap = snap_positions(graph, positions, alive, floor_z=floor)
    assert snap.status.tolist() == [0, 5, 5, 5, 0]  # SNAPPED, ON_LADDER ..., SNAPPED
    assert snap.num_airborne == 3  # counted with the frames in the air, never lost
    assert snap.ground_node.tolist() == [-1, 0, -1, 3, -1]
    down = int(np.flatnonzero((graph.edge_source == 0) & (graph.edge_target == 3))[0])
    climb = math.dist(positions[0], positions[4]) / LADDER_SPEED_M_S
    assert graph.edge_climb_s[down] == pytest.approx(climb)
    np.testing.assert_allclose(snap.ground_delay_s, [0, -0.1 / 3 * climb, 0, 0.2 / 3 * climb, 0])
    seconds = np.arange(5) * 0.5
    plan, _ = plan_player(
        graph, snap, positions, seconds, alive, np.array(["Knife"] * 5), PathCache(graph)
    )
    targets = [0, 1, 3, 4]
    assert plan.target_frame.tolist() == targets
    np.testing.assert_allclose(plan.target_seconds, (seconds + snap.ground_delay_s)[targets])
    assert down in plan.action_edge.tolist() and 2 not in plan.action_edge.tolist()


def test_a_jump_beside_a_ladders_foot_targets_the_foot_not_the_top() -> None:
    """Standing at the foot (node 3), a jump on the ladder's line that lands at the foot again:
    the frames in the air are on the ladder, but the passage leaves and reaches the foot; the
    replay stays off the ladder."""
    graph = ladder_and_drop()
    foot = graph.positions[3]
    up = np.array(
        [[0.0, 0.0, 0.0], [0.0, -0.1, 0.6], [0.0, -0.1, 0.9], [0.0, -0.1, 0.5], [0, 0, 0]]
    )
    positions = foot + up
    floor = np.zeros(5)
    alive = np.ones(5, bool)
    snap = snap_positions(graph, positions, alive, floor_z=floor)
    assert snap.ground_node.tolist() == [-1, 3, -1, 3, -1]
    seconds = np.arange(5) * 0.25
    weapons = np.array(["Knife"] * 5)
    plan, _ = plan_player(graph, snap, positions, seconds, alive, weapons, PathCache(graph))
    assert not (graph.edge_kind[plan.action_edge[plan.action_edge >= 0]] == EdgeKind.LADDER).any()


def test_a_fall_beside_a_ladder_is_no_climb() -> None:
    """Off the ledge (node 1, beside the ladder's top) down to the floor, the frames in the air
    on the ladder's line: the height changes faster than a climb between them, so they are a
    fall (in the air, over the floor), not a passage of the ladder."""
    graph = ladder_and_drop()
    positions = np.array([[0.0, 0.1, 3.0], [0.0, 0.3, 2.4], [0.0, 0.5, 0.8], [0.0, 0.7, 0.0]])
    floor = np.array([3.0, 0.0, 0.0, 0.0])
    alive = np.ones(4, bool)
    seconds = np.array([0.0, 0.2, 0.4, 0.6])
    fall = snap_positions(graph, positions, alive, floor_z=floor, seconds=seconds)
    assert fall.status.tolist() == [0, 4, 4, 0]  # SNAPPED, AIRBORNE, AIRBORNE, SNAPPED
    climb = snap_positions(graph, positions, alive, floor_z=floor, seconds=seconds * 4)
    assert climb.status.tolist() == [0, 5, 5, 0]  # the same heights at a climb's pace


def test_one_frame_on_a_ladder_targets_the_end_he_reaches() -> None:
    """Up the ladder of `ladder_and_drop` at one frame a second: at the foot, a third of the
    way up, on the ledge. The frame on the ladder targets the top when the climb puts him
    there."""
    graph = ladder_and_drop()
    positions = np.array([[0.0, 0.7, 0.0], [0.0, 0.45, 1.0], [0.0, 0.0, 3.0]])
    snap = snap_positions(graph, positions, np.ones(3, bool), floor_z=np.array([0.0, 0.0, 3.0]))
    assert snap.ground_node.tolist() == [-1, 0, -1]
    up = int(np.flatnonzero((graph.edge_source == 3) & (graph.edge_target == 0))[0])
    assert snap.ground_delay_s[1] == pytest.approx(2 / 3 * graph.edge_climb_s[up])


def two_ladders_from_one_foot() -> WaypointGraph:
    """A foot (node 0, z = 0) with a short ladder up to a landing (1, z = 2) and a long one,
    along nearly the same line, up to a roof (2, z = 4)."""
    positions = [(0.0, 0.0, 0.0), (0.0, 0.7, 2.0), (0.0, 0.8, 4.0)]
    edges = [
        (0, 1, EdgeKind.LADDER, 0),
        (1, 0, EdgeKind.LADDER, 4),
        (0, 2, EdgeKind.LADDER, 0),
        (2, 0, EdgeKind.LADDER, 4),
    ]
    return make_graph(positions, edges)


@pytest.mark.parametrize(("top", "heights"), [(2, [1.0, 3.0]), (1, [0.6, 1.4])])
def test_a_passage_climbs_the_ladder_whose_ends_it_joins(top: int, heights: list[float]) -> None:
    """Low on the ladders both fit; a passage takes the one most of its frames are on, then
    the one whose ends lie at the heights of the frames before and after it."""
    graph = two_ladders_from_one_foot()
    end = graph.positions[top]
    climbing = [[0.0, 0.3 + 0.2 * k, h] for k, h in enumerate(heights)]
    positions = np.array([[0.0, 0.0, 0.0], *climbing, end])
    floor = np.array([0.0, 0.0, 0.0, end[2]])
    snap = snap_positions(graph, positions, np.ones(4, bool), floor_z=floor)
    assert snap.ground_node.tolist() == [-1, 0, top, -1]


def test_between_a_ladders_ends_the_path_is_the_ladder() -> None:
    graph = ladder_and_drop()
    ladder_down = int(np.flatnonzero((graph.edge_source == 0) & (graph.edge_target == 3))[0])
    by_drop = graph.edge_cost[[0, 2, 3]].sum()
    assert by_drop < graph.edge_cost[ladder_down]  # the drop is the quicker way down
    assert graph.shortest_path(0, 3) == [0, 1, 2, 3]
    assert PathCache(graph).edges(0, 3).tolist() == [ladder_down]
    assert graph.edges_between(np.array([0, 0, 1]), np.array([3, 2, 2])).tolist() == [
        ladder_down,
        -1,  # no edge from 0 to 2
        2,
    ]
    assert PathCache(graph).edges(1, 3).tolist() == [2, 3]  # not from a ladder's end: shortest
