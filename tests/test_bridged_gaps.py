"""A way the graph lacks (a staircase the map's version has and the graph's world does not): the
plan crosses it as a gap, placed on the far side when the player was nearer it, instead of
sending the replay the long way round."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from test_plans import SPACING, lattice, make_graph

from decoy_cli.replay import PathCache, SnapResult, snap_positions
from decoy_cli.replay.rounds import expected_lateness, plan_player
from decoy_cli.waypoints.graph import EdgeKind, WaypointGraph

LENGTH = 30
"""Nodes along each floor: the only way between them is at the far east end, 20 m away."""

CS2_FILE = (
    Path(__file__).resolve().parents[1].parent
    / "shared/data/cs2_dust2_both/spirit-vs-falcons-m2-dust2-r01-12.json.xz"
)


def two_levels() -> WaypointGraph:
    """A floor at z = 0 along y = 0 (nodes 0..29) and a landing 2.4 m above it along y = 1.4
    (30..59), joined only at their east ends (a ramp)."""
    low, low_edges = lattice(LENGTH, 1)
    high = [(x, 2 * SPACING, 2.4) for x, _, _ in low]
    _, high_edges = lattice(LENGTH, 1, first=LENGTH)
    east = LENGTH - 1
    ramp = [(east, east + LENGTH, EdgeKind.WALK, 2), (east + LENGTH, east, EdgeKind.WALK, 6)]
    return make_graph(low + high, [*low_edges, *high_edges, *ramp])


def up_the_stairs(graph: WaypointGraph) -> tuple:
    """1 frame per second: two frames below, one on the stairs the graph lacks (off its floors,
    not snapped), two on the landing."""
    positions = np.array(
        [[0.0, 0.0, 0.0], [0.7, 0.0, 0.0], [0.7, 1.0, 1.7], [0.7, 1.4, 2.4], [1.4, 1.4, 2.4]]
    )
    alive = np.ones(5, bool)
    snap = snap_positions(graph, positions, alive)
    node, error, status = snap.node.copy(), snap.error_m.copy(), snap.status.copy()
    node[2], error[2], status[2] = -1, np.nan, 3  # NO_WAYPOINT: on the stairs
    snap = SnapResult(node, error, status, snap.ground_node, snap.ground_delay_s)
    seconds = np.arange(5, dtype=float)
    return snap, positions, seconds, alive, np.array(["Knife"] * 5)


def test_a_way_the_player_cannot_have_taken_is_crossed_as_a_gap() -> None:
    graph = two_levels()
    snap, positions, seconds, alive, weapons = up_the_stairs(graph)
    assert snap.node[3] == LENGTH + 1  # the landing
    plan, caps = plan_player(graph, snap, positions, seconds, alive, weapons, PathCache(graph))
    assert plan.target_frame.tolist() == [0, 1, 3, 4]
    assert plan.interval_unreachable.tolist() == [False, True, False]
    assert plan.interval_cross_s[1] == 2.0  # on the stairs the player is nearer the landing
    assert np.isnan(plan.interval_cross_s[[0, 2]]).all()
    assert expected_lateness(plan, caps).max() == 0.0


def test_a_way_round_the_player_could_have_run_stays() -> None:
    """Given 30 s for the climb the ramp (20 m there and back) is within the player's speed:
    no gap."""
    graph = two_levels()
    snap, positions, _, alive, weapons = up_the_stairs(graph)
    seconds = np.array([0.0, 1.0, 16.0, 31.0, 32.0])
    plan, _ = plan_player(graph, snap, positions, seconds, alive, weapons, PathCache(graph))
    assert not plan.interval_unreachable.any()
    assert np.isnan(plan.interval_cross_s).all()


@pytest.mark.skipif(not CS2_FILE.exists(), reason=f"real CS2 rounds not here: {CS2_FILE}")
def test_cs2_players_climbing_to_a_site_keep_up_with_reality() -> None:
    """Round 5 of the real CS2 rounds: m0NESY takes the stairs from under A up to the site that
    CS:GO's de_dust2 lacks; the replay crosses them as a gap rather than running round by the
    ramp, 18.7 m from reality at worst, as it did."""
    from decoy_cli.esta import load_round
    from decoy_cli.metrics import player_metrics
    from decoy_cli.replay import ReplayOptions, replay_round
    from decoy_cli.waypoints.build import builtin_graph

    round_ = load_round(f"{CS2_FILE}:5")
    result = replay_round(round_, builtin_graph(), ReplayOptions(combat=False, bomb=False))
    table = player_metrics(round_, result.trace()).set_index("player")
    assert table.loc["m0NESY", "relocations"] >= 1
    assert table.loc["m0NESY", "max_dist"] < 5.0
    assert (table["late_over_frame"] == 0).all()
