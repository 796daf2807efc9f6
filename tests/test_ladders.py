"""Ladders: read from a CS:GO `.nav` file (decoy_cli/world/nav_file.py) and a map's
`nav_ladders.csv`, joined into the lattice (decoy_cli/waypoints/ladders.py) and climbed by the
movers at the climbing speed. The nav files here are written by the tests in the format's
layout; the world is a hand-made tower whose platform only a ladder reaches."""

from __future__ import annotations

import math
import struct
from functools import cache
from pathlib import Path

import numpy as np
import pytest
from worlds import floor, make_world, seeds_of, wall, walls_around

from decoy_cli.csgo import HAMMER_TO_M, LADDER_SPEED_M_S, TICK_RATE
from decoy_cli.errors import WorldError
from decoy_cli.sim.movement import KinematicMover, PhysicsMover, kernels
from decoy_cli.waypoints.build import builtin_graph
from decoy_cli.waypoints.graph import RUN_SPEED_M_S, EdgeKind, WaypointGraph
from decoy_cli.waypoints.lattice import build_lattice
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
        read_ladders(path)


def test_the_shipped_ladders_are_the_maps_nav_files_and_nuke_has_its_five() -> None:
    assert len(load_navmesh("de_nuke").ladders) == 5
    assert len(load_navmesh("de_train").ladders) == 7
    assert len(load_navmesh("de_dust2").ladders) == 0


# ---- the lattice: a tower only a ladder climbs --------------------------------------------------

PLATFORM_Z = 3.0
"""The platform's height: far above a crouch-jump, below a fatal fall."""
FACE_X = 4.85
"""The platform's west face; the lower floor lies west of it (x 0..FACE_X), the platform east
(x FACE_X..8), both y 0..4. Walls close the lower room and the platform."""
LADDER_U = np.array([[FACE_X - 0.1, 2.0, PLATFORM_Z + 0.05, FACE_X - 0.1, 2.0, 0.05]]) / HAMMER_TO_M
"""A ladder on the face: its top just above the platform's lip, its bottom on the floor."""


def tower() -> World:
    parts = [
        floor(0.0, 0.0, FACE_X, 4.0),
        walls_around(0.0, 0.0, FACE_X, 4.0),
        floor(FACE_X, 0.0, 8.0, 4.0, PLATFORM_Z),
        wall(8.0, 0.0, 8.0, 4.0, PLATFORM_Z, PLATFORM_Z + 3.0),
        wall(FACE_X, 0.0, 8.0, 0.0, PLATFORM_Z, PLATFORM_Z + 3.0),
        wall(FACE_X, 4.0, 8.0, 4.0, PLATFORM_Z, PLATFORM_Z + 3.0),
    ]
    return make_world(parts, "tower", (1.0, 1.0, 0.0))


@cache
def tower_graph(with_ladder: bool = True) -> WaypointGraph:
    world = tower()
    with PhysicsWorld(world) as physics:
        result = build_lattice(
            physics, seeds_of(world), ladders_u=LADDER_U if with_ladder else None
        )
    return WaypointGraph(
        positions=result.positions,
        edge_source=result.edge_source,
        edge_target=result.edge_target,
        edge_kind=result.edge_kind,
        edge_direction=result.edge_direction,
        node_place=np.full(len(result.positions), -1, dtype=np.int16),
        place_names=[],
        regions={},
        meta={"stats": result.stats.as_dict()},
    )


def on_platform(graph: WaypointGraph) -> np.ndarray:
    return np.abs(graph.positions[:, 2] - PLATFORM_Z) < 0.05


def test_without_the_ladder_the_platform_has_no_waypoint() -> None:
    graph = tower_graph(with_ladder=False)
    assert not on_platform(graph).any()
    assert not (graph.edge_kind == EdgeKind.LADDER).any()


def test_the_ladder_joins_the_platform_both_ways() -> None:
    graph = tower_graph()
    top = on_platform(graph)
    assert top.sum() >= 15  # the platform is flooded from the ladder's seed
    ladder = np.flatnonzero(graph.edge_kind == EdgeKind.LADDER)
    assert len(ladder) == 2
    up, down = sorted(ladder, key=lambda e: graph.positions[graph.edge_target[e], 2])[::-1]
    assert top[graph.edge_target[up]] and not top[graph.edge_source[up]]
    assert graph.edge_source[down] == graph.edge_target[up]
    assert graph.edge_target[down] == graph.edge_source[up]
    # each end within reach of the ladder, on its floor
    bottom, top_end = LADDER_U[0, 3:] * HAMMER_TO_M, LADDER_U[0, :3] * HAMMER_TO_M
    assert np.hypot(*(graph.positions[graph.edge_source[up], :2] - bottom[:2])) <= 1.5
    assert np.hypot(*(graph.positions[graph.edge_target[up], :2] - top_end[:2])) <= 1.5
    # one edge per direction still, and the platform is in the strongly connected graph
    pairs = set(zip(graph.edge_source.tolist(), graph.edge_direction.tolist(), strict=True))
    assert len(pairs) == graph.num_edges
    stats = graph.meta["stats"]
    assert (stats["ladders"], stats["ladders_joined"], stats["edges"]["ladder"]) == (1, 1, 2)
    lengths = graph.path_lengths(int(graph.edge_source[up]))
    assert np.all(np.isfinite(lengths))


def test_a_climb_costs_the_run_it_could_have_made_in_its_time() -> None:
    graph = tower_graph()
    e = int(np.flatnonzero(graph.edge_kind == EdgeKind.LADDER)[0])
    assert graph.edge_cost[e] == pytest.approx(
        graph.edge_length[e] * RUN_SPEED_M_S / LADDER_SPEED_M_S
    )
    assert graph.edge_cost[e] > 1.5 * graph.edge_length[e]


def test_a_ladder_whose_top_has_no_floor_gets_no_edge() -> None:
    world = tower()
    in_the_air = LADDER_U.copy()
    in_the_air[0, 2] += 2.5 / HAMMER_TO_M  # its top 2.5 m above the platform
    with PhysicsWorld(world) as physics:
        result = build_lattice(physics, seeds_of(world), ladders_u=in_the_air)
    assert not (result.edge_kind == EdgeKind.LADDER).any()
    assert (result.stats.ladders, result.stats.ladders_joined) == (1, 0)


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


def test_the_shipped_nuke_graph_climbs_to_heaven_and_the_roof() -> None:
    graph = builtin_graph("de_nuke")
    ladder = graph.edge_kind == EdgeKind.LADDER
    assert ladder.sum() >= 8
    places = graph.place_names
    reached = {places[p] for p in graph.node_place[graph.edge_target[ladder]] if p >= 0}
    assert {"Heaven", "Roof"} <= reached
