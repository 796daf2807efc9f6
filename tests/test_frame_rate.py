"""Plans that keep time whatever the data's frame rate: hard targets no denser than the lattice
resolves, denser frames as soft targets, and a hard target moved to a neighbouring waypoint
where its own lies across a wall from the player's way."""

from __future__ import annotations

import numpy as np
import pytest
from test_plans import SPACING, lattice, make_graph

from decoy_cli.esta.frame_rate import describe_frame_rate, describe_rates, frame_rates
from decoy_cli.replay import PathCache, build_plan, snap_positions
from decoy_cli.replay.rounds import expected_lateness, interval_caps, plan_player
from decoy_cli.replay.targets import hard_frames, target_seconds
from decoy_cli.waypoints.graph import EdgeKind, WaypointGraph

LENGTH = 12
"""Nodes along each side of the wall."""


def walled() -> WaypointGraph:
    """Two rows of a lattice, y = 0 (nodes 0..11) and y = 0.7 (12..23), x = 0 .. 7.7, with a wall
    between them open only at the east end: from one row to the other at x < 4 is over 8 m."""
    south, south_edges = lattice(LENGTH, 1)
    north = [(x, SPACING, z) for x, _, z in south]
    _, north_edges = lattice(LENGTH, 1, first=LENGTH)
    east = LENGTH - 1
    door = [(east, east + LENGTH, EdgeKind.WALK, 2), (east + LENGTH, east, EdgeKind.WALK, 6)]
    return make_graph(south + north, [*south_edges, *north_edges, *door])


def on_the_wall(seconds: np.ndarray) -> np.ndarray:
    """A player walking east along the wall line (y = 0.35) at 1 m/s, swaying 2 cm to either
    side of it every frame: its nearest waypoint flips from one row to the other."""
    sway = np.where(np.arange(len(seconds)) % 2 == 0, -0.02, 0.02)
    x = np.minimum(seconds, SPACING * (LENGTH - 2))
    return np.stack([x, SPACING / 2 + sway, np.zeros(len(seconds))], axis=1)


def naive_and_planned(seconds: np.ndarray) -> tuple[float, float, list[int], list[int]]:
    """(the expected lateness at worst of a plan with every frame a hard target, that of
    `plan_player`'s plan, its target frames, the rows of its targets)."""
    graph = walled()
    positions = on_the_wall(seconds)
    alive = np.ones(len(seconds), bool)
    snap = snap_positions(graph, positions, alive)
    assert set((snap.node // LENGTH).tolist()) == {0, 1}  # snapping flips from row to row
    weapons = np.array(["Knife"] * len(seconds))
    naive = build_plan(graph, snap.node, seconds, alive, weapons)
    naive_late = expected_lateness(naive, interval_caps(naive, positions)).max()
    plan, caps = plan_player(graph, snap, positions, seconds, alive, weapons, PathCache(graph))
    late = expected_lateness(plan, caps).max()
    return naive_late, late, plan.target_frame.tolist(), sorted(set(plan.target_node // LENGTH))


def test_target_seconds_is_what_the_lattice_resolves() -> None:
    """0.7 m over the 30% the replay may outrun the player, at the knife's 4.76 m/s: 0.49 s, so
    ESTA's 2 frames per second are all hard targets."""
    graph = walled()
    assert target_seconds(graph) == pytest.approx(0.7 / (0.3 * 250 * 0.01905))
    assert hard_frames(np.arange(10) * 0.5, np.ones(10, bool), target_seconds(graph)).all()


def test_hard_frames_follow_the_clock_at_any_rate() -> None:
    hard = hard_frames(np.arange(17) / 8, np.ones(17, bool), 0.49)
    assert np.flatnonzero(hard).tolist() == [0, 4, 8, 12, 16]
    # the rate changes within the round (8 Hz, then 1 Hz), a repeated time, an unusable frame
    seconds = np.array([0.0, 0.125, 0.25, 0.375, 0.5, 0.5, 1.5, 2.5, 2.625, 3.0])
    usable = np.array([True, True, True, True, False, True, True, True, True, True])
    hard = hard_frames(seconds, usable, 0.49)
    assert np.flatnonzero(hard).tolist() == [0, 5, 6, 7, 9]


def test_at_8_hz_flips_across_a_wall_leave_the_plan_on_time_on_one_side() -> None:
    naive, late, frames, rows = naive_and_planned(np.arange(33) / 8)  # 4 s
    assert naive > 1.0  # every frame hard: each flip is a long way round
    assert late <= 1 / 60
    assert len(rows) == 1
    assert frames[0] == 0 and frames[-1] >= 31
    assert set(range(0, 33, 4)) <= set(frames)  # the hard targets stay


def test_at_2_hz_a_hard_target_across_the_wall_moves_to_its_neighbour() -> None:
    """At 2 frames per second every frame is a hard target; those snapped across the wall move
    to the waypoint beside them on the player's side: none is dropped."""
    naive, late, frames, rows = naive_and_planned(np.arange(9) * 0.5)
    assert naive > 1.0
    assert frames == list(range(9))
    assert len(rows) == 1
    assert late <= 1 / 60


def test_the_data_s_frame_rate_in_words() -> None:
    assert describe_frame_rate(np.arange(10) * 0.5) == "2 frames/s"
    assert describe_frame_rate(np.arange(300) / 128) == "128 frames/s"
    missing = np.delete(np.arange(20) * 0.5, 7)  # one frame missing: the rate still holds
    assert describe_frame_rate(missing) == "2 frames/s"
    changing = np.concatenate([np.arange(20) / 8, 3.0 + np.arange(10)])
    assert describe_frame_rate(changing) == "1 to 8 frames/s (changes within the round)"
    assert describe_frame_rate(np.array([1.0])) == "one frame"
    assert frame_rates(np.array([2.0, 2.0, 2.5]))[0] == pytest.approx(2.0)  # a repeat: no rate
    assert describe_rates(np.array([8.0, 8.0, np.nan])) == "8 frames/s"
    assert describe_rates(np.array([1.0, 1.0])) == "1 frame/s"
    assert describe_rates(np.array([1.0, 8.0])).startswith("1 to 8 frames/s")
    assert describe_rates(np.array([np.nan])) == "not known"


def test_near_lists_the_waypoints_on_the_point_s_floor_nearest_first() -> None:
    low, low_edges = lattice(3, 3)
    high, high_edges = lattice(3, 3, z=3.0, first=9)
    graph = make_graph(low + high, low_edges + high_edges)
    point = np.array([0.3, 0.1, 0.0])
    assert graph.near(point, 0.8).tolist() == [0, 3, 1, 4]  # 0.32, 0.41, 0.67, 0.72 m away
    upstairs = point + np.array([0, 0, 3.0])
    assert graph.near(upstairs, 0.5).tolist() == [9, 12]  # the upper floor only
    assert graph.near(point, 0.1).tolist() == []
    assert int(graph.near(point, 0.8)[0]) == int(graph.nearest(point)[0][0])
