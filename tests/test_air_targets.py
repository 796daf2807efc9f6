"""Frames in the air as soft targets (the waypoint on the floor under them, kept only where the
replay stays in time), the speed caps over an interval's running time, and the lateness a plan
is expected to run into."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest
from test_plans import SPACING, lattice, make_graph, with_drop

from decoy_cli.csgo import GRAVITY_M_S2
from decoy_cli.replay import PathCache, SnapStatus, build_plan, snap_positions
from decoy_cli.replay.rounds import expected_lateness, interval_caps, plan_player
from decoy_cli.waypoints.graph import EdgeKind, WaypointGraph
from decoy_cli.weapons import max_speed_m_s

FRAMES = 5


def over_a_lower_floor() -> WaypointGraph:
    """An upper walkway (nodes 0..4, z = 3, x = 0 .. 2.8) straight over a lower one (5..9, z = 0);
    one DROP edge from its east end (4) down to 9, nothing back up."""
    upper, upper_edges = lattice(FRAMES, 1, z=3.0)
    lower, lower_edges = lattice(FRAMES, 1, z=0.0, first=FRAMES)
    return make_graph(upper + lower, [*upper_edges, *lower_edges, (4, 9, EdgeKind.DROP, 2)])


def walkway_run(graph: WaypointGraph, floor_under_jump: float) -> dict:
    """A walk along the upper walkway, 0.7 m per 0.5 s frame, with a jump 1 m up at frame 2,
    over a floor at `floor_under_jump` (the walkway itself, or the floor below through a gap)."""
    positions = graph.positions[:FRAMES].copy()
    positions[2, 2] += 1.0
    floor = np.full(FRAMES, 3.0)
    floor[2] = floor_under_jump
    alive = np.ones(FRAMES, bool)
    snap = snap_positions(graph, positions, alive, floor_z=floor)
    return {
        "graph": graph,
        "snap": snap,
        "positions": positions,
        "seconds": np.arange(FRAMES) * 0.5,
        "alive": alive,
        "weapons": np.array(["Knife"] * FRAMES),
        "paths": PathCache(graph),
    }


def test_a_frame_in_the_air_gets_the_waypoint_on_the_floor_under_it() -> None:
    graph = over_a_lower_floor()
    snap = walkway_run(graph, floor_under_jump=3.0)["snap"]
    assert snap.status[2] == SnapStatus.AIRBORNE and snap.node[2] == -1
    assert snap.ground_node.tolist() == [-1, -1, 2, -1, -1]
    through_the_gap = walkway_run(graph, floor_under_jump=0.0)["snap"]
    assert through_the_gap.ground_node.tolist() == [-1, -1, 7, -1, -1]  # the floor below
    positions = graph.positions[:FRAMES].copy()
    positions[2, 2] += 1.0
    unknown = np.full(FRAMES, 3.0)
    unknown[2] = np.nan  # no floor found: the usual snap (the walkway, 1 m below)
    snap = snap_positions(graph, positions, np.ones(FRAMES, bool), floor_z=unknown)
    assert snap.status[2] == SnapStatus.SNAPPED and (snap.ground_node == -1).all()


def test_a_soft_target_the_replay_reaches_in_time_is_kept() -> None:
    run = walkway_run(over_a_lower_floor(), floor_under_jump=3.0)
    plan, caps = plan_player(**run)
    assert plan.target_frame.tolist() == [0, 1, 2, 3, 4]
    assert plan.target_node.tolist() == [0, 1, 2, 3, 4]
    assert not expected_lateness(plan, caps).any()
    assert len(caps) == plan.num_intervals


def test_a_soft_target_a_long_way_round_is_dropped() -> None:
    """The floor under the jump is the lower walkway, reached only by the drop at the far end
    and never left again: heading there would cross a gap of the graph, so the plan goes on
    along the upper walkway, as if the frame had no target."""
    run = walkway_run(over_a_lower_floor(), floor_under_jump=0.0)
    plan, _ = plan_player(**run)
    assert plan.target_frame.tolist() == [0, 1, 3, 4]
    assert not plan.interval_unreachable.any()
    without = build_plan(
        run["graph"], run["snap"].node, run["seconds"], run["alive"], run["weapons"]
    )
    np.testing.assert_array_equal(plan.path_node, without.path_node)


def test_the_cap_measures_the_player_over_the_running_time_as_the_plan_does() -> None:
    """A drop of 2 m then a 0.7 m run in 0.68 s with an AWP: the fall takes its air time and no
    run (the run goes on while the agent falls), so the 0.7 m left need more than the AWP's
    speed; the cap is the larger of the AWP's speed and the player's own over the running time
    (his displacement less the path's drop), times the path's zig-zag (at most 1.3): enough,
    so the replay reaches the target on time."""
    graph = with_drop()
    positions = graph.positions[[10, 4]].copy()
    seconds = np.array([0.0, 0.68])
    weapons = np.array(["AWP", "AWP"])
    snap = snap_positions(graph, positions, np.ones(2, bool))
    plan = build_plan(graph, snap.node, seconds, np.ones(2, bool), weapons)
    assert plan.path_node.tolist() == [10, 7, 4]
    fall_s = math.sqrt(2 * 2.0 / GRAVITY_M_S2)
    assert plan.interval_air_s[0] == pytest.approx(fall_s)
    required = SPACING / (0.68 - fall_s)
    assert plan.interval_required_speed_m_s[0] == pytest.approx(required)
    assert required > max_speed_m_s("AWP") and plan.interval_infeasible[0]
    drop = math.hypot(SPACING, 2.0)
    straight = np.linalg.norm(positions[1] - positions[0]) - drop
    zigzag = min(SPACING / straight, 1.3)
    own = straight / (0.68 - fall_s)
    caps = interval_caps(plan, positions)
    assert caps[0] == pytest.approx(max(max_speed_m_s("AWP"), own) * zigzag)
    assert caps[0] > required
    assert expected_lateness(plan, caps).tolist() == pytest.approx([0.0, 0.0])


def test_expected_lateness_carries_over_and_is_caught_up_at_a_stand() -> None:
    """Caps of 1.4 m/s over 1.4 m intervals of 0.5 s: each run takes 1 s. Late 0.5 s at the
    second target; standing there (no run) the agent leaves at once and is on time again; the
    last run is 0.5 s late once more."""
    graph = make_graph(*lattice(FRAMES, 1))
    positions = graph.positions[[0, 2, 2, 4]]
    snap = snap_positions(graph, positions, np.ones(4, bool))
    plan = build_plan(
        graph, snap.node, np.arange(4) * 0.5, np.ones(4, bool), np.array(["Knife"] * 4)
    )
    late = expected_lateness(plan, np.array([1.4, 1.4, 1.4]))
    assert late.tolist() == pytest.approx([0.0, 0.5, 0.0, 0.5])


def test_a_soft_target_on_the_way_stays_in_a_stretch_late_for_another_reason() -> None:
    """A walk along y = 0 of a 12 × 12 lattice, 0.7 m per 0.5 s frame, jumping at frames 2 and 4:
    the floor under the first jump is reported 7.7 m to the side (the replay would run late
    going there), under the second right on the way. The first is dropped; the second stays,
    though the replay may still be catching up there."""
    graph = make_graph(*lattice(12, 12))
    frames = 8
    on_line = [12 * i for i in range(frames)]  # node (i, 0)
    positions = graph.positions[on_line].copy()
    positions[[2, 4], 2] += 1.0
    floor = np.zeros(frames)
    alive = np.ones(frames, bool)
    snap = snap_positions(graph, positions, alive, floor_z=floor)
    aside = graph.positions[on_line[2]] + np.array([0.0, 7.7, 0.0])
    ground = snap.ground_node.copy()
    ground[2] = int(graph.nearest(aside)[0][0])
    assert ground[4] == on_line[4]
    snap = dataclasses.replace(snap, ground_node=ground)
    seconds = np.arange(frames) * 0.5
    weapons = np.array(["Knife"] * frames)
    plan, caps = plan_player(graph, snap, positions, seconds, alive, weapons, PathCache(graph))
    assert plan.target_frame.tolist() == [0, 1, 3, 4, 5, 6, 7]
    assert plan.target_node[3] == on_line[4]
    assert np.diff(expected_lateness(plan, caps)).max() <= 1 / 60  # nothing makes it later


def test_after_a_gap_the_replay_is_placed_at_once_when_late() -> None:
    """Across a gap (unreachable) the agent is placed on the target at its deadline, or at once
    when already late: lateness carries over a gap, it does not vanish."""
    graph = with_drop()  # nothing leads from the low floor back up to the high one
    positions = graph.positions[[0, 6, 10, 10]].copy()  # low, 1.4 m on, high (a gap), high
    snap = snap_positions(graph, positions, np.ones(4, bool))
    seconds = np.array([0.0, 0.5, 1.0, 1.5])
    plan = build_plan(graph, snap.node, seconds, np.ones(4, bool), np.array(["Knife"] * 4))
    assert plan.interval_unreachable.tolist() == [False, True, False]
    late = expected_lateness(plan, np.array([0.7, 5.0, 5.0]))  # 1.4 m at 0.7 m/s: 2 s
    assert late.tolist() == pytest.approx([0.0, 1.5, 1.0, 0.5])


@pytest.mark.parametrize("step_s", [0.5, 0.25])
def test_a_fall_to_a_lower_floor_is_a_target_when_he_lands(step_s: float) -> None:
    """Along the upper walkway and off its east end, 1.5 m above the lower one in the frame
    after, on it the frame after that. He is over the landing spot (node 9) in the air, but
    there only after his fall (from rest: an upper bound): the target's deadline is then, and
    with frames closer than the fall it is left out (the next frame says where he is)."""
    graph = over_a_lower_floor()
    positions = np.vstack(
        [graph.positions[:FRAMES], graph.positions[9] + [0.0, 0.0, 1.5], graph.positions[9]]
    )
    floor = np.array([3.0] * FRAMES + [0.0, 0.0])
    alive = np.ones(FRAMES + 2, bool)
    snap = snap_positions(graph, positions, alive, floor_z=floor)
    fall = math.sqrt(2 * 1.5 / GRAVITY_M_S2)
    assert snap.ground_node[FRAMES] == 9
    assert snap.ground_delay_s[FRAMES] == pytest.approx(fall)
    seconds = np.arange(FRAMES + 2) * step_s
    weapons = np.array(["Knife"] * (FRAMES + 2))
    plan, _ = plan_player(graph, snap, positions, seconds, alive, weapons, PathCache(graph))
    kept = fall <= step_s
    assert (FRAMES in plan.target_frame.tolist()) == kept
    if kept:
        assert plan.target_seconds[plan.target_frame == FRAMES][0] == pytest.approx(
            seconds[FRAMES] + fall
        )
