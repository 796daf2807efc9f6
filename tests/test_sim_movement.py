"""The movers on hand-made worlds (tests/worlds.py) and on the real de_dust2 graph: timing along
paths, speed caps, jumps, drops, two-floor spots, agents blocking each other, bounded stuck
recovery, removed agents, rays against agent capsules, and determinism."""

from __future__ import annotations

import math
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from functools import cache

import numpy as np
import pytest
from worlds import (
    BOX_Z,
    DECK,
    DECK_Z,
    LEDGE_Z,
    floor,
    graph_of,
    jump_box_world,
    ledge_world,
    make_world,
    overpass_world,
    room,
    seeds_of,
    wall,
)

from decoy_cli.csgo import GRAVITY_M_S2, JUMP_SPEED_M_S, PLAYER_HEIGHT_M, TICK_RATE
from decoy_cli.sim.movement import (
    DEFAULT_MAX_SPEED_M_S,
    KinematicMover,
    MoverBase,
    MoveStep,
    PhysicsMover,
    layout,
)
from decoy_cli.waypoints.build import builtin_graph
from decoy_cli.waypoints.graph import EdgeKind, WaypointGraph
from decoy_cli.waypoints.lattice import LatticeParams, build_lattice
from decoy_cli.world.navmesh import nav_world
from decoy_cli.world.physics import AGENT_GROUP, WORLD_GROUP, PhysicsWorld
from decoy_cli.world.world import World

DT = 1 / TICK_RATE
MOVERS = ("kinematic", "physics")
CORRIDOR_Y = (2.6, 3.4)
"""The corridor's walls: 0.8 m apart around the lattice line y = 3, room for one capsule
(0.49 m wide) but not for two side by side."""


def corridor_world() -> World:
    """An 8 m long corridor (x 0..8) of `CORRIDOR_Y`, closed at both ends."""
    y0, y1 = CORRIDOR_Y
    return make_world(
        [
            floor(0.0, y0, 8.0, y1),
            wall(0.0, y0, 8.0, y0, 0.0, 3.0),
            wall(0.0, y1, 8.0, y1, 0.0, 3.0),
            wall(0.0, y0, 0.0, y1, 0.0, 3.0),
            wall(8.0, y0, 8.0, y1, 0.0, 3.0),
        ],
        "corridor",
        (1.0, 3.0, 0.0),
    )


WORLDS: dict[str, Callable[[], World]] = {
    "room": room,
    "jump box": jump_box_world,
    "ledge": ledge_world,
    "overpass": overpass_world,
    "corridor": corridor_world,
}


@cache
def world_graph(name: str) -> tuple[World, WaypointGraph]:
    """A hand-made world and its waypoint graph (built once per test process)."""
    world = WORLDS[name]()
    with PhysicsWorld(world) as physics:
        return world, graph_of(build_lattice(physics, seeds_of(world)))


@contextmanager
def mover_in(kind: str, world: World, **options: float) -> Iterator[MoverBase]:
    """A mover of the given kind; the physics one lives in a fresh pybullet client."""
    with PhysicsWorld(world) as physics:
        yield KinematicMover() if kind == "kinematic" else PhysicsMover(physics, **options)


def node_at(graph: WaypointGraph, point: tuple[float, float, float]) -> int:
    index, _ = graph.nearest(np.asarray(point, dtype=np.float64))
    assert index[0] >= 0
    return int(index[0])


def drive(
    mover: MoverBase,
    graph: WaypointGraph,
    paths: list[list[int]],
    speed: float,
    ticks: int,
    watch: Callable[[int, MoveStep], None] | None = None,
) -> tuple[list[list[int]], np.ndarray]:
    """Walk each agent along its node path as the engine does (the next edge is given at the
    tick after an arrival). Returns the tick of every node reached per agent (0 for the start)
    and the feet positions at every tick, (T + 1, N, 3)."""
    edge_of = {
        (u, v): k
        for k, (u, v) in enumerate(
            zip(graph.edge_source.tolist(), graph.edge_target.tolist(), strict=True)
        )
    }
    mover.reset(graph.positions[[path[0] for path in paths]])
    reached = [[0] for _ in paths]

    def give(a: int) -> None:
        k = len(reached[a])
        if k < len(paths[a]):
            edge = edge_of[(paths[a][k - 1], paths[a][k])]
            mover.set_goal(a, graph.positions[paths[a][k]], int(graph.edge_kind[edge]), speed)

    for a in range(len(paths)):
        give(a)
    trace = [mover.positions.copy()]
    for tick in range(1, ticks + 1):
        step = mover.step()
        trace.append(mover.positions.copy())
        if watch is not None:
            watch(tick, step)
        for a in np.flatnonzero(step.arrived).tolist():
            reached[a].append(tick)
            give(a)
        alive = mover.alive
        if all(
            len(r) == len(p) or not alive[a]
            for a, (r, p) in enumerate(zip(reached, paths, strict=True))
        ):
            break
    return reached, np.asarray(trace)


def ticks_for(seconds: float) -> int:
    """The tick at which a motion of this duration ends."""
    return math.ceil(seconds / DT - 1e-6)


def rise_seconds(height: float) -> float:
    """Time a jump takes to lift the feet by `height` (a crouch-jump where a jump is short)."""
    v0 = max(JUMP_SPEED_M_S, math.sqrt(2 * GRAVITY_M_S2 * height))
    return (v0 - math.sqrt(max(0.0, v0 * v0 - 2 * GRAVITY_M_S2 * height))) / GRAVITY_M_S2


# ---- walking and timing -------------------------------------------------------------------------


@pytest.mark.parametrize("kind", MOVERS)
def test_one_edge_takes_its_length_over_the_speed(kind: str) -> None:
    """0.7 m at 2 m/s: 21 ticks (± 1), and the agent ends exactly on the node."""
    world, graph = world_graph("room")
    a = node_at(graph, (2.5, 2.5, 0.0))
    b = node_at(graph, (3.2, 2.5, 0.0))
    with mover_in(kind, world) as mover:
        reached, trace = drive(mover, graph, [[a, b]], 2.0, 60)
    assert abs(reached[0][1] - 21) <= 1
    np.testing.assert_allclose(trace[-1, 0], graph.positions[b], atol=1e-9)


@pytest.mark.parametrize("kind", MOVERS)
def test_a_path_keeps_time_and_hits_every_node(kind: str) -> None:
    """Along a path of straight and diagonal edges, every node is reached at the tick its
    cumulative length gives: time left over at an arrival carries into the next edge, so the
    path does not lose a fraction of a tick per edge."""
    world, graph = world_graph("room")
    path = graph.shortest_path(node_at(graph, (0.4, 0.4, 0.0)), node_at(graph, (4.6, 3.2, 0.0)))
    assert len(path) >= 6
    speed = 3.3
    with mover_in(kind, world) as mover:
        reached, trace = drive(mover, graph, [path], speed, 400)
    lengths = np.linalg.norm(np.diff(graph.positions[path], axis=0), axis=1)
    expected = [0] + [ticks_for(s / speed) for s in np.cumsum(lengths)]
    assert np.max(np.abs(np.asarray(reached[0]) - expected)) <= 1
    for node, tick in zip(path, reached[0], strict=True):
        assert np.linalg.norm(trace[tick, 0] - graph.positions[node]) <= 1e-9
    # one tick of motion never covers more than the speed allows (plus the carried time)
    step = np.linalg.norm(np.diff(trace[:, 0], axis=0), axis=1)
    assert step.max() <= 2 * speed * DT


@pytest.mark.parametrize("kind", MOVERS)
def test_speed_is_capped_by_the_agents_max_speed(kind: str) -> None:
    world, graph = world_graph("room")
    a = node_at(graph, (2.5, 2.5, 0.0))
    b = node_at(graph, (3.2, 2.5, 0.0))
    c = node_at(graph, (3.9, 2.5, 0.0))
    with mover_in(kind, world) as mover:
        mover.reset(graph.positions[[a]], max_speed=1.0)
        mover.set_goal(0, graph.positions[b], EdgeKind.WALK, 10.0)
        ticks = next(t for t in range(1, 200) if mover.step().arrived[0])
        assert abs(ticks - 42) <= 1  # 0.7 m at 1 m/s
        mover.set_max_speed(0, 3.5)
        mover.set_goal(0, graph.positions[c], EdgeKind.WALK, 10.0)
        ticks = next(t for t in range(1, 200) if mover.step().arrived[0])
        assert abs(ticks - 12) <= 1  # 0.7 m at 3.5 m/s
        mover.reset(graph.positions[[a]])  # default cap: the knife speed
        mover.set_goal(0, graph.positions[b], EdgeKind.WALK, 100.0)
        ticks = next(t for t in range(1, 200) if mover.step().arrived[0])
        assert abs(ticks - ticks_for(0.7 / DEFAULT_MAX_SPEED_M_S)) <= 1


@pytest.mark.parametrize("kind", MOVERS)
def test_moving_heading_and_standing_still(kind: str) -> None:
    """Heading is the yaw of the motion (0 = +x, 90 = +y); an agent without a goal stands
    still and is not moving; clear_goal stops a walk mid-edge."""
    world, graph = world_graph("room")
    a = node_at(graph, (2.5, 2.5, 0.0))
    east = node_at(graph, (3.2, 2.5, 0.0))
    north = node_at(graph, (2.5, 3.2, 0.0))
    with mover_in(kind, world) as mover:
        mover.reset(graph.positions[[a, a]] + [[0, 0, 0], [0, -1.4, 0]])
        mover.set_goal(0, graph.positions[east], EdgeKind.WALK, 2.0)
        step = mover.step()
        assert step.moving.tolist() == [True, False]
        assert mover.heading[0] == pytest.approx(0.0)
        for _ in range(30):
            mover.step()
        mover.set_goal(0, graph.positions[north] + [0.7, 0, 0], EdgeKind.WALK, 2.0)
        mover.step()
        assert mover.heading[0] == pytest.approx(90.0)
        mover.clear_goal(0)
        here = mover.positions[0].copy()
        step = mover.step()
        assert not step.moving[0] and not step.arrived[0]
        np.testing.assert_array_equal(mover.positions[0], here)
        with pytest.raises(ValueError, match="read-only"):
            mover.positions[0, 0] = 1.0


# ---- jumps, drops, two floors -------------------------------------------------------------------


def first_edge(graph: WaypointGraph, kind: EdgeKind, where: Callable[[int], bool]) -> int:
    edges = [e for e in np.flatnonzero(graph.edge_kind == kind).tolist() if where(e)]
    assert edges, f"no {kind.name} edge in the graph"
    return edges[0]


@pytest.mark.parametrize("kind", MOVERS)
def test_jump_onto_the_box(kind: str) -> None:
    """A jump rises in place to the box top, then moves over it: it lands on top at BOX_Z, at
    the time the rise and the walk take, and never moves sideways below the top (which would
    put the feet inside the box)."""
    world, graph = world_graph("jump box")
    e = first_edge(
        graph, EdgeKind.JUMP, lambda e: abs(graph.positions[graph.edge_target[e], 2] - BOX_Z) < 1e-6
    )
    u, v = int(graph.edge_source[e]), int(graph.edge_target[e])
    speed = 2.0
    with mover_in(kind, world) as mover:
        reached, trace = drive(mover, graph, [[u, v]], speed, 200)
    feet = trace[:, 0]
    assert feet[-1, 2] == pytest.approx(BOX_Z, abs=1e-9)
    np.testing.assert_allclose(feet[-1], graph.positions[v], atol=1e-9)
    horizontal = np.linalg.norm(graph.positions[v, :2] - graph.positions[u, :2])
    expected = ticks_for(rise_seconds(BOX_Z - graph.positions[u, 2]) + horizontal / speed)
    assert abs(reached[0][1] - expected) <= 1
    # the time in the air the planner and the replay count (edge_air_s) is the mover's
    assert graph.edge_air_s[e] == pytest.approx(rise_seconds(BOX_Z - graph.positions[u, 2]))
    moved = np.linalg.norm(feet[:, :2] - feet[0, :2], axis=1) > 1e-9
    assert np.all(feet[moved, 2] >= BOX_Z - 1e-9)
    assert feet[:, 2].max() <= BOX_Z + 1e-9 and feet[:, 2].min() >= -1e-9


@pytest.mark.parametrize("kind", MOVERS)
def test_drop_from_the_ledge(kind: str) -> None:
    """Off a ledge the run goes on while the agent falls with gravity (as a player keeps his
    speed in the air): it lands on the lower floor over the landing waypoint, never rises above
    the platform nor sinks below the floor, and takes the fall time when its run would be over
    the landing sooner; the planner counts the edge as that fall and no run."""
    world, graph = world_graph("ledge")
    e = first_edge(
        graph,
        EdgeKind.DROP,
        lambda e: (
            abs(graph.positions[graph.edge_source[e], 2] - LEDGE_Z) < 1e-6
            and abs(graph.positions[graph.edge_target[e], 2]) < 1e-6
        ),
    )
    u, v = int(graph.edge_source[e]), int(graph.edge_target[e])
    speed = 3.0
    with mover_in(kind, world) as mover:
        reached, trace = drive(mover, graph, [[u, v]], speed, 200)
    feet = trace[:, 0]
    np.testing.assert_allclose(feet[-1], graph.positions[v], atol=1e-9)
    assert feet[:, 2].max() <= LEDGE_Z + 1e-9 and feet[:, 2].min() >= -1e-9
    horizontal = np.linalg.norm(graph.positions[v, :2] - graph.positions[u, :2])
    fall = math.sqrt(2 * LEDGE_Z / GRAVITY_M_S2)
    assert horizontal / speed < fall  # the run alone would be over the landing first
    assert abs(reached[0][1] - ticks_for(fall)) <= 1
    assert graph.edge_air_s[e] == pytest.approx(fall)  # what the planner and the replay count
    assert graph.edge_run_m[e] == 0.0
    assert np.all(np.diff(feet[:, 2]) <= 1e-12)  # down only


@pytest.mark.parametrize("kind", MOVERS)
def test_an_airborne_agent_lands_before_it_stops(kind: str) -> None:
    world, graph = world_graph("jump box")
    e = first_edge(graph, EdgeKind.JUMP, lambda e: True)
    u, v = int(graph.edge_source[e]), int(graph.edge_target[e])
    with mover_in(kind, world) as mover:
        mover.reset(graph.positions[[u]])
        mover.set_goal(0, graph.positions[v], EdgeKind.JUMP, 2.0)
        ticks = 1
        while not mover.step().arrived[0]:  # told to stop at every tick: rising, then over
            mover.clear_goal(0)
            with pytest.raises(ValueError, match="in the air"):
                mover.set_goal(0, graph.positions[u], EdgeKind.DROP, 2.0)
            ticks += 1
            assert ticks < 200
        assert ticks > 20
        np.testing.assert_allclose(mover.positions[0], graph.positions[v], atol=1e-9)


@pytest.mark.parametrize("kind", MOVERS)
def test_under_the_bridge_arrival_is_on_the_lower_floor(kind: str) -> None:
    """A walk on the ground under the deck reaches the ground waypoint (z = 0), in the time of
    the walk, even with another agent standing on the deck right above it: arrival and
    blocking are 3-D, not x-y only."""
    world, graph = world_graph("overpass")
    x0, y0, x1, y1 = DECK
    under = node_at(graph, ((x0 + x1) / 2, (y0 + y1) / 2, 0.0))
    above = node_at(graph, (*graph.positions[under, :2], DECK_Z))
    assert graph.positions[above, 2] == pytest.approx(DECK_Z)
    start = node_at(graph, (graph.positions[under, 0], y0 - 2.5, 0.0))
    path = graph.shortest_path(start, under)
    assert all(graph.positions[n, 2] < 0.01 for n in path)
    speed = 4.0
    with mover_in(kind, world) as mover:
        reached, trace = drive(mover, graph, [path, [above]], speed, 300)
    assert trace[reached[0][-1], 0, 2] == pytest.approx(0.0, abs=1e-9)
    np.testing.assert_allclose(trace[-1, 0], graph.positions[under], atol=1e-9)
    np.testing.assert_allclose(trace[-1, 1], graph.positions[above], atol=0)
    length = np.linalg.norm(np.diff(graph.positions[path], axis=0), axis=1).sum()
    assert abs(reached[0][-1] - ticks_for(length / speed)) <= 1
    index, _ = graph.nearest(trace[-1, 0])
    assert index[0] == under


# ---- agents that block each other ---------------------------------------------------------------


def capsule_overlaps(mover: PhysicsMover, trace: np.ndarray) -> float:
    """Deepest horizontal overlap between two agents' capsules over a trace (0 if none)."""
    deepest = 0.0
    n = trace.shape[1]
    for a in range(n):
        for b in range(a + 1, n):
            same_height = np.abs(trace[:, a, 2] - trace[:, b, 2]) < mover.capsule_length
            gap = np.linalg.norm(trace[:, a, :2] - trace[:, b, :2], axis=1)
            overlap = np.where(same_height, 2 * mover.radius - gap, 0.0)
            deepest = max(deepest, float(overlap.max()))
    return deepest


def enters_world(mover: PhysicsMover, trace: np.ndarray) -> bool:
    """True if a capsule of the trace penetrates the world deeper than the graze tolerance."""
    centres = trace.reshape(-1, 3) + np.array(
        [0.0, 0.0, mover.float_height + mover.capsule_length / 2]
    )
    blocked = mover.physics.capsules_blocked(
        centres, mover.radius, mover.capsule_length, mover.graze
    )
    return bool(blocked.any())


def test_head_on_in_an_open_room_passes_without_teleport() -> None:
    """Two agents walking at each other on one lattice line step aside and pass: no overlap,
    no teleport, and only a little later than a free walk."""
    world, graph = world_graph("room")
    west, east = node_at(graph, (0.4, 2.5, 0.0)), node_at(graph, (4.6, 2.5, 0.0))
    paths = [graph.shortest_path(west, east), graph.shortest_path(east, west)]
    speed = 3.0
    with PhysicsWorld(world) as physics:
        mover = PhysicsMover(physics)
        reached, trace = drive(mover, graph, paths, speed, 600)
        assert all(len(r) == len(p) for r, p in zip(reached, paths, strict=True))
        assert mover.recoveries.tolist() == [0, 0]
        assert capsule_overlaps(mover, trace) <= 1e-9
        assert not enters_world(mover, trace)
    free = ticks_for(np.linalg.norm(graph.positions[east] - graph.positions[west]) / speed)
    assert max(reached[0][-1], reached[1][-1]) <= free + 60


def test_head_on_in_a_one_agent_corridor_is_resolved_by_bounded_recovery() -> None:
    """Two agents meet face to face in a corridor too narrow to pass: neither may wait forever.
    Each is declared stuck (reported in the step and counted), sidesteps are tried, and the
    last resort puts one on its goal (counted in recoveries); both then reach their ends.
    Nobody ever enters the walls."""
    world, graph = world_graph("corridor")
    west, east = node_at(graph, (1.0, 3.0, 0.0)), node_at(graph, (7.3, 3.0, 0.0))
    paths = [graph.shortest_path(west, east), graph.shortest_path(east, west)]
    flagged = np.zeros(2, dtype=np.int64)
    teleported = np.zeros(2, dtype=np.int64)

    def watch(tick: int, step: MoveStep) -> None:
        flagged[:] += step.stuck
        teleported[:] += step.teleported

    with PhysicsWorld(world) as physics:
        mover = PhysicsMover(physics)
        reached, trace = drive(mover, graph, paths, 3.0, 1200, watch)
        assert all(len(r) == len(p) for r, p in zip(reached, paths, strict=True))
        assert mover.recoveries.sum() >= 1
        assert flagged.tolist() == mover.stuck_events.tolist()
        assert teleported.tolist() == mover.recoveries.tolist()
        assert (mover.stuck_events > mover.recoveries).all()  # sidesteps came first
        assert not enters_world(mover, trace)
    # bound: per edge at most (max_sidesteps + 1) stuck periods and the sidesteps between them
    per_edge = 3 * mover.stuck_ticks + 2 * (mover.sidestep_ticks + 2 * mover.wait_ticks)
    free = ticks_for(6.3 / 3.0)
    assert max(reached[0][-1], reached[1][-1]) <= free + 2 * per_edge


def test_an_agent_next_to_one_standing_on_its_goal_has_arrived() -> None:
    """A waypoint taken by a standing agent is reached as closely as a player can get; the walk
    then goes on past it (by the bounded recovery in a corridor)."""
    world, graph = world_graph("corridor")
    path = graph.shortest_path(node_at(graph, (1.0, 3.0, 0.0)), node_at(graph, (6.6, 3.0, 0.0)))
    blocker = path[4]
    with PhysicsWorld(world) as physics:
        mover = PhysicsMover(physics)
        reached, trace = drive(mover, graph, [path, [blocker]], 3.0, 900)
        assert len(reached[0]) == len(path)
        at_blocker = trace[reached[0][4], 0]
        gap = np.linalg.norm(at_blocker[:2] - graph.positions[blocker, :2])
        assert 2 * mover.radius - 0.01 <= gap <= 2 * mover.radius + 0.1
        assert mover.recoveries[0] == 1 and mover.recoveries[1] == 0
        np.testing.assert_array_equal(trace[:, 1], trace[:1, 1].repeat(len(trace), 0))


def test_removed_agents_neither_move_nor_block() -> None:
    """An agent removed mid-walk stays where it died, and another walks through that spot in
    the time of a free walk; no ray hits its capsule any more."""
    world, graph = world_graph("corridor")
    path = graph.shortest_path(node_at(graph, (1.0, 3.0, 0.0)), node_at(graph, (7.3, 3.0, 0.0)))
    middle = len(path) // 2
    speed = 3.0
    dead_at = []

    def kill_at_tick_2(tick: int, step: MoveStep) -> None:
        if tick == 2:
            mover.remove(1)
            dead_at.append(mover.positions[1].copy())
            with pytest.raises(ValueError, match="removed"):
                mover.set_goal(1, graph.positions[path[0]], EdgeKind.WALK, speed)

    with PhysicsWorld(world) as physics:
        mover = PhysicsMover(physics)
        paths = [path, path[middle:]]
        reached, trace = drive(mover, graph, paths, speed, 600, kill_at_tick_2)
        assert not mover.alive[1] and mover.alive[0]
        assert np.all(trace[2:, 1] == dead_at[0])
        assert mover.stuck_events.sum() == 0
        length = np.linalg.norm(np.diff(graph.positions[path], axis=0), axis=1).sum()
        assert abs(reached[0][-1] - ticks_for(length / speed)) <= 1
        mover.sync_bodies()
        hit = physics._p.rayTestBatch(
            [[dead_at[0][0], 2.7, 1.0]],
            [[dead_at[0][0], 3.3, 1.0]],
            collisionFilterMask=WORLD_GROUP | AGENT_GROUP,
            physicsClientId=physics.client,
        )
        assert hit[0][0] == -1


def test_rays_hit_agents_only_when_asked() -> None:
    """Capsules are in AGENT_GROUP: a world-only ray passes through them, a ray whose mask has
    the agent bit hits them (at their synced position)."""
    world, graph = world_graph("room")
    centre = graph.positions[node_at(graph, (2.5, 2.5, 0.0))]
    with PhysicsWorld(world) as physics:
        mover = PhysicsMover(physics)
        mover.reset(centre[None, :])
        p = physics._p
        start, end = [[0.5, centre[1], 1.0]], [[4.5, centre[1], 1.0]]

        def cast(mask: int) -> int:
            return p.rayTestBatch(
                start, end, collisionFilterMask=mask, physicsClientId=physics.client
            )[0][0]

        assert cast(WORLD_GROUP) == -1
        assert cast(WORLD_GROUP | AGENT_GROUP) == int(mover.body_ids[0])
        assert physics.line_of_sight(np.array(start), np.array(end))[0]
        mover.set_goal(0, centre + np.array([0.0, 0.7, 0.0]), EdgeKind.WALK, 4.0)
        while not mover.step().arrived[0]:
            pass
        mover.sync_bodies()
        assert cast(WORLD_GROUP | AGENT_GROUP) == -1


# ---- determinism and the real map ---------------------------------------------------------------


def random_walk(graph: WaypointGraph, mover: MoverBase, agents: int, ticks: int, seed: int):
    rng = np.random.default_rng(seed)
    node = rng.choice(graph.num_nodes, size=agents, replace=False)
    mover.reset(graph.positions[node])
    trace = np.zeros((ticks, agents, 3))

    def give(a: int) -> None:
        edges = graph.out_edges[node[a]]
        edge = int(rng.choice(edges[edges >= 0]))
        node[a] = graph.edge_target[edge]
        mover.set_goal(a, graph.positions[node[a]], int(graph.edge_kind[edge]), 4.0)

    for a in range(agents):
        give(a)
    for tick in range(ticks):
        step = mover.step()
        trace[tick] = mover.positions
        for a in np.flatnonzero(step.arrived).tolist():
            give(a)
    return trace


def test_physics_mover_is_deterministic() -> None:
    """Two runs of a crowded random walk give identical trajectories and counters."""
    world, graph = world_graph("room")
    runs = []
    for _ in range(2):
        with PhysicsWorld(world) as physics:
            mover = PhysicsMover(physics)
            trace = random_walk(graph, mover, 12, 600, seed=3)
            runs.append((trace, mover.stuck_events.copy(), mover.recoveries.copy()))
    np.testing.assert_array_equal(runs[0][0], runs[1][0])
    np.testing.assert_array_equal(runs[0][1], runs[1][1])
    np.testing.assert_array_equal(runs[0][2], runs[1][2])
    assert capsule_overlaps(mover, runs[0][0]) < 0.05  # brief overlaps only


def test_edge_motion_stays_out_of_the_real_world() -> None:
    """On de_dust2, the shared edge motion of walk, step, jump and drop edges (a sample of
    each) keeps the capsule out of the world: the path the waypoint builder verified, which is
    why an agent on its edge needs no world test. (de_dust2 has no ladders: a climb, the one
    unverified path, passes over a ladder's lip.)"""
    graph = builtin_graph()
    rng = np.random.default_rng(0)
    kinds = [k for k in EdgeKind if k != EdgeKind.LADDER]
    edges = np.concatenate(
        [rng.choice(np.flatnonzero(graph.edge_kind == k), 60, replace=False) for k in kinds]
    )
    mover = KinematicMover()
    mover.reset(graph.positions[graph.edge_source[edges]])
    for a, e in enumerate(edges.tolist()):
        mover.set_goal(a, graph.positions[graph.edge_target[e]], int(graph.edge_kind[e]), 4.7)
    trace, done = [mover.positions.copy()], np.zeros(len(edges), dtype=bool)
    for _ in range(200):
        done |= mover.step().arrived
        trace.append(mover.positions.copy())
        if done.all():
            break
    assert done.all()
    np.testing.assert_allclose(mover.positions, graph.positions[graph.edge_target[edges]])
    params = LatticeParams()
    float_h = params.step_height + params.verify_clearance
    cap = PLAYER_HEIGHT_M - float_h
    with PhysicsWorld(nav_world()) as physics:
        centres = np.asarray(trace).reshape(-1, 3) + np.array([0.0, 0.0, float_h + cap / 2])
        blocked = physics.capsules_blocked(centres, params.agent_radius, cap, params.graze)
    assert not blocked.any()


def test_physics_agents_on_the_real_map_stay_out_of_walls_and_each_other() -> None:
    graph = builtin_graph()
    with PhysicsWorld(nav_world()) as physics:
        mover = PhysicsMover(physics)
        spawn = graph.region_of("t_spawn")
        rng = np.random.default_rng(1)
        mover_trace = random_walk_from(graph, mover, rng.choice(spawn, 10, replace=False), 600)
        assert not enters_world(mover, mover_trace[::5])
        assert capsule_overlaps(mover, mover_trace) < 0.05


def random_walk_from(
    graph: WaypointGraph, mover: MoverBase, start: np.ndarray, ticks: int
) -> np.ndarray:
    rng = np.random.default_rng(7)
    node = np.asarray(start).copy()
    mover.reset(graph.positions[node])
    trace = np.zeros((ticks, len(node), 3))

    def give(a: int) -> None:
        edges = graph.out_edges[node[a]]
        edge = int(rng.choice(edges[edges >= 0]))
        node[a] = graph.edge_target[edge]
        mover.set_goal(a, graph.positions[node[a]], int(graph.edge_kind[edge]), 4.0)

    for a in range(len(node)):
        give(a)
    for tick in range(ticks):
        step = mover.step()
        trace[tick] = mover.positions
        for a in np.flatnonzero(step.arrived).tolist():
            give(a)
    return trace


# ---- bad input ----------------------------------------------------------------------------------


def test_bad_input_raises_value_errors() -> None:
    world, graph = world_graph("room")
    with PhysicsWorld(world) as physics:
        for mover in (KinematicMover(), PhysicsMover(physics)):
            with pytest.raises(ValueError, match="positions"):
                mover.reset(np.zeros((2, 2)))
            with pytest.raises(ValueError, match="max_speed"):
                mover.reset(np.zeros((2, 3)), max_speed=[1.0, 2.0, 3.0])
            mover.reset(graph.positions[:2])
            with pytest.raises(ValueError, match="no agent"):
                mover.set_goal(2, graph.positions[0], EdgeKind.WALK, 1.0)
            with pytest.raises(ValueError, match="speed"):
                mover.set_goal(0, graph.positions[1], EdgeKind.WALK, -1.0)
            with pytest.raises(ValueError, match="speed"):
                mover.set_goal(0, graph.positions[1], EdgeKind.WALK, float("nan"))
            with pytest.raises(ValueError, match="target"):
                mover.set_goal(0, [0.0, np.nan, 0.0], EdgeKind.WALK, 1.0)
            with pytest.raises(ValueError):
                mover.set_goal(0, graph.positions[1], 7, 1.0)
        with pytest.raises(ValueError, match="radius"):
            PhysicsMover(physics, radius=0.8)


# ---- the packed state's slot names and the capsule's dimensions ------------------------------


@pytest.mark.parametrize(
    ("prefix", "count"),
    [
        ("F_", "FLOAT_SLOTS"),
        ("I_", "INT_SLOTS"),
        ("S_", None),
        ("R_", "FLAG_ROWS"),
        ("P_", "PARAM_SLOTS"),
    ],
)
def test_slot_names_number_each_slot_once(prefix: str, count: str | None) -> None:
    names = [n for n in vars(layout) if n.startswith(prefix)]
    if count is None:  # the scratch arrays: a float and an int one share the prefix
        floats = {"S_VZ", "S_LEFT"}
        groups = [(floats, "SCRATCH_FLOAT_SLOTS"), (set(names) - floats, "SCRATCH_INT_SLOTS")]
    else:
        groups = [(set(names), count)]
    for group, size in groups:
        slots = sorted(getattr(layout, n) for n in group)
        assert slots == list(range(getattr(layout, size))), (group, size)
    phases = [layout.IDLE, layout.RISE, layout.LINE, layout.GLIDE, layout.FALL]
    assert sorted(phases) == list(range(5))


def test_physics_capsule_is_the_one_the_waypoint_builder_verified() -> None:
    world, _ = world_graph("room")
    params = LatticeParams()
    with PhysicsWorld(world) as physics:
        mover = PhysicsMover(physics)
        assert mover.radius == params.agent_radius
        assert mover.float_height == params.step_height + params.verify_clearance
        assert mover.graze == params.graze
        mover.close()


def test_the_kernels_edge_kind_constants_are_the_graphs() -> None:
    from decoy_cli.sim.movement import kernels

    assert (kernels.JUMP_EDGE, kernels.DROP_EDGE) == (EdgeKind.JUMP, EdgeKind.DROP)
