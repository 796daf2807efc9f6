"""Snapping, gap filling and timed plans on small hand-made waypoint graphs."""

from __future__ import annotations

import math
from types import SimpleNamespace
from typing import Any

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from decoy_cli.csgo import GRAVITY_M_S2, LADDER_SPEED_M_S
from decoy_cli.errors import EstaError, GraphError
from decoy_cli.replay import (
    RELOCATE_ACTION,
    SUMMARY_COLUMNS,
    PathCache,
    PlayerPlan,
    SnapStatus,
    build_plan,
    snap_positions,
    snap_round,
)
from decoy_cli.waypoints.graph import (
    DIRECTION_VECTORS,
    RUN_SPEED_M_S,
    STOP_ACTION,
    EdgeKind,
    WaypointGraph,
)

SPACING = 0.7
KNIFE_M_S = 250 * 0.01905  # 4.7625
AK_M_S = 215 * 0.01905  # 4.09575
DIAGONAL = SPACING * math.sqrt(2)


def make_graph(
    positions: list[tuple[float, float, float]], edges: list[tuple[int, int, int, int]]
) -> WaypointGraph:
    """A graph from node positions and (source, target, kind, direction) edges."""
    e = np.array(edges, dtype=np.int64).reshape(-1, 4)
    return WaypointGraph(
        positions=np.array(positions, dtype=np.float64),
        edge_source=e[:, 0].astype(np.int32),
        edge_target=e[:, 1].astype(np.int32),
        edge_kind=e[:, 2].astype(np.uint8),
        edge_direction=e[:, 3].astype(np.uint8),
        node_place=np.full(len(positions), -1, dtype=np.int16),
        place_names=[],
        regions={},
    )


def lattice(
    nx: int, ny: int, z: float = 0.0, x0: float = 0.0, first: int = 0
) -> tuple[list[tuple[float, float, float]], list[tuple[int, int, int, int]]]:
    """Positions and 8-direction WALK edges of an nx × ny lattice; node (i, j) = first + i*ny + j.

    Node (i, j) lies at (x0 + 0.7 i, 0.7 j, z).
    """
    positions = [(x0 + SPACING * i, SPACING * j, z) for i in range(nx) for j in range(ny)]
    edges = []
    for i in range(nx):
        for j in range(ny):
            for d, (di, dj) in enumerate(DIRECTION_VECTORS):
                if 0 <= i + di < nx and 0 <= j + dj < ny:
                    edges.append(
                        (first + i * ny + j, first + (i + di) * ny + j + dj, EdgeKind.WALK, d)
                    )
    return positions, edges


def grid5() -> WaypointGraph:
    """5 × 5 lattice at z = 0, 0.7 m spacing, node (i, j) = 5i + j at (0.7 i, 0.7 j)."""
    return make_graph(*lattice(5, 5))


def node(i: int, j: int) -> int:
    """Index of lattice node (i, j) in `grid5`."""
    return 5 * i + j


def at(*nodes: int, graph: WaypointGraph | None = None) -> np.ndarray:
    """Positions of lattice nodes (one frame per node)."""
    return (graph or grid5()).positions[list(nodes)].copy()


def two_floors() -> WaypointGraph:
    """Two 3 × 3 floors at the same x-y, z = 0 (nodes 0..8) and z = 3 (nodes 9..17)."""
    low, low_edges = lattice(3, 3, z=0.0)
    high, high_edges = lattice(3, 3, z=3.0, first=9)
    return make_graph(low + high, low_edges + high_edges)


def with_drop() -> WaypointGraph:
    """A low 3 × 3 floor (0..8, z = 0) and a high one east of it (9..17, z = 2).

    One DROP edge leads west from the high node 10 (2.1, 0.7, 2) down to the low node 7
    (1.4, 0.7, 0); nothing leads back up, so the high floor is unreachable from the low one.
    """
    low, low_edges = lattice(3, 3, z=0.0)
    high, high_edges = lattice(3, 3, z=2.0, x0=3 * SPACING, first=9)
    return make_graph(low + high, [*low_edges, *high_edges, (10, 7, EdgeKind.DROP, 6)])


def plan_for(
    graph: WaypointGraph,
    positions: np.ndarray,
    seconds: list[float] | None = None,
    weapons: list[str] | None = None,
    alive: list[bool] | np.ndarray | None = None,
    **kwargs: Any,
) -> PlayerPlan:
    """Snap positions and build the plan (defaults: frames 0.5 s apart, alive, knife)."""
    positions = np.asarray(positions, dtype=np.float64)
    frames = len(positions)
    seconds = np.arange(frames) * 0.5 if seconds is None else np.asarray(seconds, float)
    alive = np.ones(frames, bool) if alive is None else np.asarray(alive, bool)
    weapons = np.array(["Knife"] * frames if weapons is None else weapons)
    snap = snap_positions(graph, positions, alive)
    return build_plan(graph, snap.node, seconds, alive, weapons, **kwargs)


def check_action_chain(graph: WaypointGraph, plan: PlayerPlan) -> None:
    """Every move crosses one edge from where the agent is, in that edge's compass direction."""
    here = plan.target_node[0]
    for code, edge, reached in zip(plan.action, plan.action_edge, plan.action_node, strict=True):
        if code == STOP_ACTION:
            assert edge == -1 and reached == here
        elif code == RELOCATE_ACTION:
            assert edge == -1
        else:
            assert graph.edge_source[edge] == here and graph.edge_target[edge] == reached
            assert code == graph.edge_direction[edge]
            delta = graph.positions[reached] - graph.positions[here]
            np.testing.assert_allclose(delta[:2], DIRECTION_VECTORS[code] * SPACING, atol=1e-9)
        here = reached


# ---- snapping --------------------------------------------------------------------------------


def test_snap_finds_nearest_waypoint_and_error() -> None:
    graph = grid5()
    positions = np.array([[0.1, 0.05, 0.0], [1.45, 2.1, 0.2], [2.8, 2.8, 0.0]])
    snap = snap_positions(graph, positions, np.ones(3, bool))
    assert snap.node.tolist() == [node(0, 0), node(2, 3), node(4, 4)]
    np.testing.assert_allclose(snap.error_m, [math.hypot(0.1, 0.05), math.hypot(0.05, 0.2), 0])
    assert snap.num_snapped == 3


def test_snap_reasons_for_unsnapped_frames() -> None:
    graph = grid5()
    positions = np.array(
        [
            [0.0, 0.0, 0.0],  # snapped
            [0.7, 0.0, 0.0],  # dead: not snapped even with a position
            [np.nan, np.nan, np.nan],  # alive without a position
            [10.0, 10.0, 0.0],  # off the graph, beyond the snap distance
            [0.7, 0.7, 5.0],  # far above every floor
        ]
    )
    alive = np.array([True, False, True, True, True])
    snap = snap_positions(graph, positions, alive)
    assert snap.node.tolist() == [0, -1, -1, -1, -1]
    assert snap.error_m[0] == 0 and np.isnan(snap.error_m[1:]).all()
    assert snap.status.tolist() == [
        SnapStatus.SNAPPED,
        SnapStatus.NOT_ALIVE,
        SnapStatus.NO_POSITION,
        SnapStatus.NO_WAYPOINT,
        SnapStatus.NO_WAYPOINT,
    ]
    assert snap.counts() == {
        "SNAPPED": 1,
        "NOT_ALIVE": 1,
        "NO_POSITION": 1,
        "NO_WAYPOINT": 2,
        "AIRBORNE": 0,
        "ON_LADDER": 0,
    }
    assert snap.num_unsnappable == 2


def test_snap_max_distance_is_configurable() -> None:
    graph = grid5()
    far = np.array([[-1.0, 0.0, 0.0]])  # 1 m west of node 0
    assert snap_positions(graph, far, np.ones(1, bool)).node.tolist() == [0]
    tight = snap_positions(graph, far, np.ones(1, bool), max_distance=0.5)
    assert tight.status.tolist() == [SnapStatus.NO_WAYPOINT]


def test_snap_is_floor_aware() -> None:
    graph = two_floors()
    positions = np.array([[0.75, 0.7, 3.05], [0.75, 0.7, 0.1], [0.7, 0.7, 1.9]])
    snap = snap_positions(graph, positions, np.ones(3, bool))
    assert snap.node.tolist() == [9 + 4, 4, -1]
    assert snap.status[2] == SnapStatus.NO_WAYPOINT


def test_snap_leaves_frames_in_the_air_unsnapped() -> None:
    """A frame more than AIRBORNE_M above the world's floor is a jump or a fall: not snapped,
    whatever floor lies near; where the floor is unknown (NaN) the frame snaps as usual."""
    graph = grid5()
    positions = np.array(
        [[0.0, 0.0, 0.0], [0.7, 0.0, 0.3], [1.4, 0.0, 0.9], [2.1, 0.0, 0.9], [2.8, 0.0, 0.0]]
    )
    floor = np.array([0.0, 0.0, 0.0, np.nan, 0.0])
    snap = snap_positions(graph, positions, np.ones(5, bool), floor_z=floor)
    assert snap.status.tolist() == [
        SnapStatus.SNAPPED,
        SnapStatus.SNAPPED,  # 0.3 m up: a step or a stair, not the air
        SnapStatus.AIRBORNE,
        SnapStatus.SNAPPED,  # floor unknown: the usual rule (a node up to 1.25 m below)
        SnapStatus.SNAPPED,
    ]
    assert snap.node[2] == -1 and np.isnan(snap.error_m[2])
    assert snap.counts()["AIRBORNE"] == 1
    with pytest.raises(EstaError, match="floor heights"):
        snap_positions(graph, positions, np.ones(5, bool), floor_z=np.zeros(4))


def test_snap_rejects_bad_shapes() -> None:
    with pytest.raises(EstaError, match="positions"):
        snap_positions(grid5(), np.zeros((4, 2)), np.ones(4, bool))
    with pytest.raises(EstaError, match="alive"):
        snap_positions(grid5(), np.zeros((4, 3)), np.ones(3, bool))


# ---- paths and actions -----------------------------------------------------------------------


def test_gap_filled_by_shortest_path_along_edges() -> None:
    graph = grid5()
    plan = plan_for(graph, at(node(0, 0), node(4, 2)), seconds=[0.0, 2.0])
    assert plan.path_node[0] == node(0, 0) and plan.path_node[-1] == node(4, 2)
    assert len(plan.path_node) == 5  # 4 edges: 2 diagonal + 2 east
    assert plan.interval_length_m[0] == pytest.approx(2 * DIAGONAL + 2 * SPACING)
    assert len(plan.action) == 4
    check_action_chain(graph, plan)
    assert sorted(plan.action.tolist()) == [1, 1, 2, 2]  # NE, NE, E, E
    np.testing.assert_allclose(plan.action_node, plan.path_node[1:])
    # each move's planned time is its share of the interval at uniform speed
    assert plan.action_duration_s.sum() == pytest.approx(2.0)
    np.testing.assert_allclose(
        plan.action_duration_s,
        2.0 * graph.edge_length[plan.action_edge] / (2 * DIAGONAL + 2 * SPACING),
    )
    assert plan.path_deadline_s.tolist() == [0.0, 2.0, 2.0, 2.0, 2.0]
    assert plan.target_path_index.tolist() == [0, 4]


def test_directed_one_way_drop_is_used_downhill() -> None:
    graph = with_drop()
    plan = plan_for(graph, at(10, 7, graph=graph), seconds=[0.0, 1.0])
    assert plan.path_node.tolist() == [10, 7]
    assert plan.action.tolist() == [6]  # W
    assert graph.edge_kind[plan.action_edge[0]] == EdgeKind.DROP
    assert plan.num_unreachable == 0


def test_unreachable_target_is_recorded_and_relocated() -> None:
    graph = with_drop()
    # high 10 -> low 7 (drop), low 7 -> high 11 (no way up), high 11 -> high 14 (walk east)
    plan = plan_for(graph, at(10, 7, 11, 14, graph=graph), seconds=[0.0, 1.0, 2.0, 3.0])
    assert plan.interval_unreachable.tolist() == [False, True, False]
    assert plan.num_unreachable == 1
    assert np.isnan(plan.interval_length_m[1]) and np.isnan(plan.interval_speed_ratio[1])
    assert not plan.interval_infeasible[1]
    assert plan.path_node.tolist() == [10, 7, 11, 14]
    assert plan.action.tolist() == [6, RELOCATE_ACTION, 2]
    assert plan.action_edge[1] == -1 and plan.action_node[1] == 11
    assert plan.action_deadline_s.tolist() == [1.0, 2.0, 3.0]
    check_action_chain(graph, plan)
    assert plan.total_length_m == pytest.approx(graph.edge_length[plan.action_edge[0]] + 0.7)
    # the drop is crossed in its fall (no run), so the worst interval is the last: 0.7 m in 1 s
    assert plan.interval_required_speed_m_s[0] == 0.0
    assert plan.worst_ratio == pytest.approx(0.7 / 1.0 / KNIFE_M_S)
    assert plan.action_duration_s[0] == pytest.approx(1.0)


def test_an_interval_is_shared_by_air_time_first_then_by_length() -> None:
    """A drop (2 m, a safe fall) then a walk in one 2 s interval: the fall takes sqrt(2 h / g)
    and no run (the run goes on while the agent falls), the walk's 0.7 m has the rest."""
    graph = with_drop()
    plan = plan_for(graph, at(10, 8, graph=graph), seconds=[0.0, 2.0])
    assert plan.path_node.tolist() == [10, 7, 8]
    drop = plan.action_edge[0]
    fall_s = math.sqrt(2 * 2.0 / GRAVITY_M_S2)
    assert graph.edge_air_s[drop] == pytest.approx(fall_s) and graph.edge_run_m[drop] == 0.0
    assert plan.interval_required_speed_m_s[0] == pytest.approx(0.7 / (2.0 - fall_s))
    assert graph.edge_cost[drop] == pytest.approx(RUN_SPEED_M_S * fall_s)  # no fall damage


def test_standing_still_ten_seconds_is_ten_seconds_of_stop() -> None:
    graph = grid5()
    plan = plan_for(graph, at(*[node(2, 2)] * 21))  # 21 frames, 0.5 s apart
    assert plan.num_intervals == 20
    assert plan.action.tolist() == [STOP_ACTION] * 20
    assert plan.action_duration_s.tolist() == [0.5] * 20
    assert plan.stop_seconds == pytest.approx(10.0)
    assert plan.path_node.tolist() == [node(2, 2)] * 21
    assert plan.total_length_m == 0 and plan.num_infeasible == 0
    assert (plan.interval_required_speed_m_s == 0).all()


def test_wait_then_move_keeps_both() -> None:
    graph = grid5()
    plan = plan_for(graph, at(*[node(1, 1)] * 9, node(1, 2)))  # wait 4 s, then one step north
    assert plan.action.tolist() == [STOP_ACTION] * 8 + [0]
    assert plan.stop_seconds == pytest.approx(4.0)
    assert plan.action_duration_s[-1] == pytest.approx(0.5)
    assert plan.action_deadline_s[-1] == 4.5


# ---- speed feasibility ------------------------------------------------------------------------


def test_infeasible_interval_and_ratio() -> None:
    graph = grid5()
    plan = plan_for(
        graph,
        at(node(0, 0), node(4, 0), node(4, 1)),
        weapons=["AK-47", "Knife", "Knife"],
    )
    # 4 edges east = 2.8 m in 0.5 s = 5.6 m/s with an AK-47 (215 u/s = 4.09575 m/s)
    assert plan.interval_length_m.tolist() == pytest.approx([2.8, 0.7])
    assert plan.interval_required_speed_m_s.tolist() == pytest.approx([5.6, 1.4])
    assert plan.interval_max_speed_m_s.tolist() == pytest.approx([AK_M_S, KNIFE_M_S])
    assert plan.interval_speed_ratio[0] == pytest.approx(5.6 / AK_M_S)
    assert plan.interval_speed_ratio[1] == pytest.approx(1.4 / KNIFE_M_S)
    assert plan.interval_infeasible.tolist() == [True, False]
    assert plan.num_infeasible == 1
    assert plan.worst_ratio == pytest.approx(5.6 / AK_M_S)
    # straight east: too fast even in a straight line, not the graph's way round
    assert plan.interval_detour.tolist() == [False, False]


def test_an_interval_too_fast_only_by_the_way_round_is_a_detour() -> None:
    """Two nodes 0.7 m apart with no edge between them: the way round is 2.1 m, too far for an
    AK-47 in 0.5 s, the straight line is not."""
    graph = make_graph(
        [(0.0, 0.0, 0.0), (0.7, 0.0, 0.0), (0.7, 0.7, 0.0), (0.0, 0.7, 0.0)],
        [(0, 3, 0, 2), (3, 2, 0, 0), (2, 1, 0, 6), (1, 0, 0, 4)],
    )
    plan = plan_for(graph, at(0, 1, graph=graph), weapons=["AK-47", "AK-47"])
    assert plan.interval_length_m.tolist() == pytest.approx([2.1])
    assert plan.interval_infeasible.tolist() == [True]
    assert plan.interval_detour.tolist() == [True]
    assert plan.interval_zigzag.tolist() == [False]  # three times the straight line


def test_a_detour_within_the_lattices_zig_zag() -> None:
    """From (0, 0) to (2, 1) on the lattice: one straight step and one diagonal, 1.69 m against
    1.57 m straight (1.08 times, the most a lattice path takes); in 0.4 s an AK-47 runs 1.64 m."""
    graph = grid5()
    plan = plan_for(graph, at(node(0, 0), node(2, 1)), seconds=[0.0, 0.4], weapons=["AK-47"] * 2)
    assert plan.interval_detour.tolist() == [True]
    assert plan.interval_zigzag.tolist() == [True]


def test_speed_uses_weapon_at_interval_start_and_no_weapon_is_knife() -> None:
    graph = grid5()
    plan = plan_for(graph, at(node(0, 0), node(4, 0), node(0, 0)), weapons=["", "AWP", "Knife"])
    assert plan.interval_max_speed_m_s.tolist() == pytest.approx([KNIFE_M_S, 200 * 0.01905])
    assert plan.interval_speed_ratio.tolist() == pytest.approx([5.6 / KNIFE_M_S, 5.6 / 3.81])


def test_unknown_weapon_raises() -> None:
    with pytest.raises(EstaError, match="unknown weapon 'Banana'"):
        plan_for(grid5(), at(0, 1), weapons=["Banana", "Knife"])


def test_interval_table_lists_every_interval() -> None:
    plan = plan_for(grid5(), at(node(0, 0), node(4, 0), node(4, 1)), weapons=["AK-47"] * 3)
    table = plan.interval_table()
    assert len(table) == 2
    assert table["infeasible"].tolist() == [True, False]
    assert table["detour"].tolist() == table["zigzag"].tolist() == [False, False]
    assert table[["from_node", "to_node"]].values.tolist() == [[0, 20], [20, 21]]
    assert table["ratio"].iloc[0] == pytest.approx(5.6 / AK_M_S)


# ---- alive, death and gaps --------------------------------------------------------------------


def test_alive_at_end_survives() -> None:
    plan = plan_for(grid5(), at(0, 1, 2, 3))
    assert not plan.died and plan.death_frame == -1 and math.isnan(plan.death_seconds)
    assert plan.target_frame.tolist() == [0, 1, 2, 3]
    assert plan.last_alive_frame == 3


def test_death_mid_round_ends_plan() -> None:
    alive = [True, True, True, True, False, False]
    plan = plan_for(grid5(), at(0, 1, 2, 3, 3, 3), alive=alive)
    assert plan.target_frame.tolist() == [0, 1, 2, 3]
    assert plan.died and plan.death_frame == 4 and plan.death_seconds == 2.0
    assert plan.last_alive_frame == 3
    assert plan.action_deadline_s.max() == 1.5


def test_player_vanishing_from_the_data_is_not_killed() -> None:
    graph = grid5()
    positions = at(0, 1, 2, 3, 4)
    positions[3:] = np.nan
    alive = np.array([True, True, True, False, False])
    snap = snap_positions(graph, positions, alive)
    present = np.isfinite(positions).all(axis=1)
    plan = build_plan(
        graph, snap.node, np.arange(5) * 0.5, alive, np.array(["Knife"] * 5), present=present
    )
    assert plan.target_frame.tolist() == [0, 1, 2]
    assert not plan.died


def test_missing_frames_in_the_middle_are_joined() -> None:
    graph = grid5()
    positions = at(node(0, 0), node(0, 1), node(0, 2), 0, 0, 0, node(3, 2), node(3, 3))
    positions[3:5] = np.nan  # absent
    positions[5] = [0.7, 0.7, 9.0]  # alive but on no floor
    alive = np.array([True, True, True, False, False, True, True, True])
    plan = plan_for(graph, positions, alive=alive)
    assert plan.target_frame.tolist() == [0, 1, 2, 6, 7]
    assert plan.interval_skipped_frames.tolist() == [0, 0, 3, 0]
    assert plan.interval_seconds[2] == pytest.approx(2.0)
    assert plan.interval_length_m[2] == pytest.approx(2.1)
    assert plan.interval_required_speed_m_s[2] == pytest.approx(1.05)
    assert plan.action_deadline_s[plan.action_interval == 2].tolist() == [3.0, 3.0, 3.0]
    assert not plan.died and plan.num_unreachable == 0
    check_action_chain(graph, plan)


def test_never_alive_gives_an_empty_plan() -> None:
    plan = plan_for(grid5(), at(0, 1), alive=[False, False])
    assert plan.is_empty and not plan.died
    assert plan.num_intervals == 0 and len(plan.path_node) == 0 and len(plan.action) == 0
    assert math.isnan(plan.worst_ratio)


def test_single_target_has_no_actions() -> None:
    plan = plan_for(grid5(), at(3))
    assert plan.path_node.tolist() == [3] and len(plan.action) == 0


# ---- inputs and the path cache ----------------------------------------------------------------


def test_path_cache_computes_each_pair_once(monkeypatch: pytest.MonkeyPatch) -> None:
    graph = grid5()
    calls = []
    original = graph.shortest_path

    def counting(source: int, target: int) -> list[int]:
        calls.append((source, target))
        return original(source, target)

    monkeypatch.setattr(graph, "shortest_path", counting)
    cache = PathCache(graph)
    positions = at(node(0, 0), node(2, 2), node(0, 0), node(2, 2), node(2, 2))
    plan_for(graph, positions, paths=cache)
    plan_for(graph, positions, paths=cache)
    assert sorted(calls) == [(0, 12), (12, 0)]
    assert len(cache) == 2


def test_path_cache_of_another_graph_is_refused() -> None:
    with pytest.raises(GraphError, match="another"):
        plan_for(grid5(), at(0, 1), paths=PathCache(grid5()))


def test_build_plan_rejects_bad_inputs() -> None:
    graph = grid5()
    ok = dict(frame_seconds=[0.0, 0.5], alive=[True, True], weapons=["Knife"] * 2)
    with pytest.raises(EstaError, match="weapons"):
        build_plan(graph, [0, 1], **{**ok, "weapons": ["Knife"]})
    with pytest.raises(EstaError, match="non-decreasing"):
        build_plan(graph, [0, 1], **{**ok, "frame_seconds": [1.0, 0.5]})
    with pytest.raises(GraphError, match="outside"):
        build_plan(graph, [0, 25], **ok)


@settings(max_examples=60, deadline=None)
@given(
    st.lists(
        st.tuples(st.integers(0, 24), st.booleans(), st.floats(0.0, 2.0)), min_size=1, max_size=30
    )
)
def test_plan_invariants_on_random_walks(frames: list[tuple[int, bool, float]]) -> None:
    graph = grid5()
    nodes = np.array([f[0] for f in frames])
    alive = np.array([f[1] for f in frames])
    seconds = np.cumsum([f[2] for f in frames])
    plan = build_plan(graph, np.where(alive, nodes, -1), seconds, alive, ["Knife"] * len(frames))
    assert plan.target_frame.tolist() == np.flatnonzero(alive).tolist()
    if plan.is_empty:
        return
    check_action_chain(graph, plan)
    assert (plan.path_node[plan.target_path_index] == plan.target_node).all()
    for k in range(plan.num_intervals):
        a, b = plan.target_node[k], plan.target_node[k + 1]
        assert plan.interval_length_m[k] == pytest.approx(graph.path_lengths(a)[0][b])
        durations = plan.action_duration_s[plan.action_interval == k]
        assert durations.sum() == pytest.approx(plan.interval_seconds[k])
    stops = np.count_nonzero(plan.action == STOP_ACTION)
    assert stops == np.count_nonzero(np.diff(plan.target_node) == 0)
    assert plan.died == (not alive[-1])


# ---- whole rounds -----------------------------------------------------------------------------


def fake_round() -> tuple[SimpleNamespace, WaypointGraph]:
    """Two players over 6 frames on the 5 × 5 lattice, in the reader's `Round` layout."""
    graph = grid5()
    offset = np.array([0.1, 0.0, 0.0])
    a = at(*[node(0, j) for j in range(5)], node(0, 4)) + offset
    b = at(node(2, 0), node(0, 1), node(2, 2), node(2, 2), node(2, 2), node(2, 2)) + offset
    b[1] = [-0.6, 0.7, 0.0]  # snapped to node (0, 1), 0.6 m off
    b[2] = [1.4, 1.4, 6.0]  # alive but on no floor
    alive = np.array([[True] * 6, [True, True, True, True, False, False]])
    weapon = np.array([["AK-47"] * 6, ["Knife"] * 4 + ["", ""]])
    return SimpleNamespace(
        position=np.stack([a, b]),
        alive=alive,
        weapon=weapon,
        frame_seconds=np.arange(6) * 0.5,
        frame_ticks=np.arange(6) * 64,
        players=[
            SimpleNamespace(key="p0", name="T-slot-0", steam_id=None, side="T"),
            SimpleNamespace(key="p1", name="T-slot-1", steam_id=None, side="T"),
        ],
    ), graph


def test_snap_round_builds_plans_and_summary() -> None:
    round_, graph = fake_round()
    result = snap_round(round_, graph)
    assert len(result.plans) == 2 and len(result.snaps) == 2
    summary = result.summary
    assert list(summary.columns) == list(SUMMARY_COLUMNS)
    first, second = summary.iloc[0], summary.iloc[1]
    assert first["player"] == "T-slot-0" and first["side"] == "T"
    assert first["frames_alive"] == 6 and second["frames_alive"] == 4
    assert first["snap_median_m"] == pytest.approx(0.1)
    assert first["snap_max_m"] == pytest.approx(0.1)
    assert first["within_0.5m"] == 1.0
    assert second["snap_max_m"] == pytest.approx(0.6)
    assert second["within_0.5m"] == pytest.approx(2 / 4)  # 0.1, 0.6, 0.1 m and one unsnappable
    assert first["unsnappable"] == 0 and second["unsnappable"] == 1
    assert first["intervals"] == 5 and second["intervals"] == 2
    assert first["path_length_m"] == pytest.approx(2.8)
    assert first["worst_ratio"] == pytest.approx(1.4 / AK_M_S)
    assert first["infeasible"] == 0 and first["unreachable"] == 0
    assert math.isnan(first["died_s"]) and second["died_s"] == 2.0
    assert result.num_unsnappable == 1 and result.num_infeasible == 0
    assert result.num_unreachable == 0


def test_snap_round_rejects_inconsistent_arrays() -> None:
    round_, graph = fake_round()
    round_.alive = round_.alive[:, :5]
    with pytest.raises(EstaError, match="alive"):
        snap_round(round_, graph)


@settings(max_examples=200, deadline=None)
@given(st.lists(st.integers(1, 40), min_size=1, max_size=30), st.integers(0, 2**32 - 1))
def test_interval_sums_round_exactly_as_numpy_sums_each_run(runs: list[int], seed: int) -> None:
    """`build_plan` sums every interval's edge lengths in one pass; each sum must be bit for bit
    the `ndarray.sum` of the interval's run, so that plans (and replays) do not move by a
    rounding when the code is reorganised."""
    from decoy_cli.replay.plans import _interval_sums

    rng = np.random.default_rng(seed)
    steps = np.array(runs, dtype=np.int64)
    values = rng.random(int(steps.sum())) * rng.choice([1e-3, 1.0, 1e3], int(steps.sum()))
    starts = np.cumsum(steps) - steps
    sums = _interval_sums(values, starts, steps)
    expected = np.array([values[a : a + n].sum() for a, n in zip(starts, steps, strict=True)])
    assert sums.tobytes() == expected.tobytes()


# ---- ladders ------------------------------------------------------------------------------------


def with_ladder() -> WaypointGraph:
    """A low walkway (nodes 0..5, z = 0, x 0 .. 3.5) and a high one beyond it (6..11, z = 2,
    x 4.2 .. 7.7), joined by a ladder from 5 up to 6 and back (2.12 m long)."""
    low, low_edges = lattice(6, 1, z=0.0)
    high, high_edges = lattice(6, 1, z=2.0, x0=6 * SPACING, first=6)
    ladders = [(5, 6, EdgeKind.LADDER, 2), (6, 5, EdgeKind.LADDER, 6)]
    return make_graph(low + high, [*low_edges, *high_edges, *ladders])


def test_a_ladder_is_planned_as_its_climb_and_the_rest_as_a_run() -> None:
    graph = with_ladder()
    climb = math.hypot(SPACING, 2.0) / LADDER_SPEED_M_S
    plan = plan_for(graph, at(0, 6, graph=graph), seconds=[0.0, 1.5])
    assert plan.interval_run_m[0] == pytest.approx(5 * SPACING)  # the climb is not run
    assert plan.interval_length_m[0] == pytest.approx(5 * SPACING + math.hypot(SPACING, 2.0))
    assert plan.interval_air_s[0] == pytest.approx(climb)
    assert plan.interval_required_speed_m_s[0] == pytest.approx(5 * SPACING / (1.5 - climb))
    assert not plan.interval_infeasible[0]  # 4.45 m/s: a knife runs it
    assert plan.action_duration_s[-1] == pytest.approx(climb)  # the ladder, last
    assert plan.action_duration_s.sum() == pytest.approx(1.5)
    alone = plan_for(graph, at(5, 6, graph=graph), seconds=[0.0, 2.0])
    assert alone.interval_required_speed_m_s[0] == 0.0
    assert alone.action_duration_s.tolist() == [pytest.approx(2.0)]  # no NaN: all by the climb
