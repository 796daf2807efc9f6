"""Synthetic rounds over each kind of edge: the player's motion by CS:GO's rules (checked by
hand), and replays of samples that follow it within 0.5 m on maps with every kind."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from decoy_cli.csgo import GRAVITY_M_S2, JUMP_SPEED_M_S, LADDER_SPEED_M_S
from decoy_cli.esta import read_match
from decoy_cli.esta.writer import write_match
from decoy_cli.metrics import player_metrics
from decoy_cli.replay import ReplayOptions, replay_round
from decoy_cli.synth.edge_rounds import KINDS, edge_match, edge_motion
from decoy_cli.waypoints.build import builtin_graph
from decoy_cli.waypoints.graph import EdgeKind
from decoy_cli.weapons import max_speed_m_s

TOP = np.array([0.0, 0.0, 3.0])


def test_off_a_ledge_the_player_runs_on_while_he_falls() -> None:
    # 0.6 m across and 3 m down at 4 m/s: the run is over long before the landing
    took, at = edge_motion(TOP, np.array([0.6, 0.0, 0.0]), EdgeKind.DROP, 4.0)
    fall = math.sqrt(2 * 3.0 / GRAVITY_M_S2)
    assert took == pytest.approx(fall)
    np.testing.assert_allclose(at(0.1), [0.4, 0.0, 3.0 - GRAVITY_M_S2 * 0.01 / 2])
    np.testing.assert_allclose(at(took), [0.6, 0.0, 0.0])
    # 4 m across and 0.5 m down: the landing comes first, the run takes its time
    took, at = edge_motion(TOP, np.array([4.0, 0.0, 2.5]), EdgeKind.DROP, 4.0)
    assert took == pytest.approx(1.0)
    assert at(0.9)[2] == 2.5


def test_a_jump_rises_while_the_player_runs_and_ends_at_the_top() -> None:
    # 0.3 m up: a plain jump (take-off speed), first at that height on the way up
    took, at = edge_motion(TOP, TOP + np.array([0.2, 0.0, 0.3]), EdgeKind.JUMP, 4.0)
    v = JUMP_SPEED_M_S
    rise = (v - math.sqrt(v * v - 2 * GRAVITY_M_S2 * 0.3)) / GRAVITY_M_S2
    assert took == pytest.approx(max(0.2 / 4.0, rise))
    assert at(took)[2] == pytest.approx(3.3)
    # higher than a plain jump reaches: the take-off that just gets there
    took, _ = edge_motion(TOP, TOP + np.array([0.2, 0.0, 1.5]), EdgeKind.JUMP, 4.0)
    assert took == pytest.approx(math.sqrt(2 * 1.5 / GRAVITY_M_S2))


def test_walks_and_ladders_are_straight_at_their_speed() -> None:
    end = TOP + np.array([3.0, 4.0, 0.0])
    took, at = edge_motion(TOP, end, EdgeKind.WALK, 2.5)
    assert took == pytest.approx(2.0)
    np.testing.assert_allclose(at(1.0), TOP + np.array([1.5, 2.0, 0.0]))
    took, _ = edge_motion(TOP, TOP + np.array([0.0, 0.0, 5.0]), EdgeKind.LADDER, 2.5)
    assert took == pytest.approx(5.0 / LADDER_SPEED_M_S)


@pytest.mark.parametrize(
    ("map_name", "rate", "seed"), [("mirage", 2.0, 0), ("mirage", 4.0, 0), ("nuke", 8.0, 1)]
)
def test_every_kind_of_edge_replays_within_half_a_metre(
    tmp_path: Path, map_name: str, rate: float, seed: int
) -> None:
    """de_mirage and de_nuke have every kind (ladders too; two of de_nuke's share a foot):
    three rounds per kind, drops without fall damage, the runner at 90% of the knife's speed,
    at the frame rates and seeds where a mid-air frame, a ladder passage or a drop with time to
    spare once put the replay more than 0.5 m off."""
    graph = builtin_graph(map_name)
    record, kinds = edge_match(graph, 3, seed, 0.9 * max_speed_m_s("Knife"), rate)
    assert sorted(set(kinds)) == sorted(KINDS) and len(kinds) == 12
    rounds = read_match(write_match(record, tmp_path / "edges.json.xz")).rounds
    for round_, kind in zip(rounds, kinds, strict=True):
        replay = replay_round(round_, graph, ReplayOptions(combat=False, bomb=False))
        row = player_metrics(round_, replay.trace()).iloc[0]
        assert row["mean_dist"] <= 0.5, (kind.name, row.to_dict())
