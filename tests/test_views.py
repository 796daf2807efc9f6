"""Where replayed players look: the data's view in the combat step (decoy_cli/replay/views.py)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from both_teams import BothTeams, Mate, site_node

from decoy_cli.esta import read_match
from decoy_cli.replay.replayer import ReplayOptions, replay_round
from decoy_cli.replay.views import DataViews, data_views
from decoy_cli.sim.combat import NO_HIT, CombatBatch, DamageResult, VisiblePairs, make_batch
from decoy_cli.sim.state import Agents
from decoy_cli.waypoints.build import builtin_graph


def test_views_turn_the_short_way_between_frames_and_fall_back_by_hand() -> None:
    views = DataViews(np.array([0, 60, 120]), np.array([[350.0, 10.0, np.nan], [np.nan, 90, 90]]))
    assert views(30) == pytest.approx([0.0, 90.0], abs=1e-9)  # 350 -> 10 through 0; one known
    assert views(45) == pytest.approx([5.0, 90.0])
    assert views(60) == pytest.approx([10.0, 90.0])
    at_90 = views(90)  # the frame after has no view: the one before's
    assert at_90[0] == pytest.approx(10.0) and at_90[1] == pytest.approx(90.0)
    last = views(500)  # past the data: the last frame's, unknown for the first player
    assert np.isnan(last[0]) and last[1] == pytest.approx(90.0)
    first = views(-5)  # before the data: the first frame's
    assert first[0] == pytest.approx(350.0) and np.isnan(first[1])
    assert data_views(np.array([0, 60]), np.full((2, 2), np.nan)) is None


def test_a_known_view_stands_for_the_agents_yaw_in_the_batch() -> None:
    agents = Agents.create(
        names=["t", "ct"],
        sides=["T", "CT"],
        positions=np.array([[0.0, 0.0, 0.0], [10.0, 0.0, 0.0]]),
        nodes=np.array([0, 1]),
        yaw=np.array([180.0, 0.0]),  # both look away from each other
    )
    pairs = VisiblePairs(np.array([0, 1]), np.array([1, 0]))
    moving = make_batch(agents, pairs, "de_dust2")
    assert moving.bearing == pytest.approx([-np.pi, -np.pi])
    viewed = make_batch(agents, pairs, "de_dust2", np.array([0.0, np.nan]))
    assert viewed.attacker_yaw == pytest.approx([0.0, 0.0])  # the second keeps its own yaw
    assert viewed.bearing == pytest.approx([0.0, -np.pi])


class _Watching:
    """A damage model that never hits and keeps the attackers' yaws it was shown."""

    def __init__(self) -> None:
        self.yaws: list[float] = []

    def __call__(self, batch: CombatBatch, rng: np.random.Generator) -> DamageResult:
        self.yaws += batch.attacker_yaw.tolist()
        k = len(batch)
        return DamageResult(np.zeros(k, np.int64), np.full(k, NO_HIT, np.int8), np.zeros(k, bool))


@pytest.mark.parametrize("view", [123.0, None])
def test_the_replay_shoots_where_the_data_looks(tmp_path: Path, view: float | None) -> None:
    a, b = site_node("bombsite_a", 0), site_node("bombsite_a", 3)
    doc = BothTeams(
        frames=4,
        players=[
            Mate("t", "T", [a], weapon="AK-47", view=view),
            Mate("ct", "CT", [b], weapon="M4A4", view=view),
        ],
    )
    round_ = read_match(doc.write(tmp_path / "views.json")).rounds[0]
    watching = _Watching()
    result = replay_round(round_, builtin_graph(), ReplayOptions(damage_model=watching))
    assert watching.yaws, "the two players never saw each other: pick other waypoints"
    if view is not None:
        assert watching.yaws == pytest.approx([view] * len(watching.yaws))
        assert not any(note.startswith("view") for note in result.inferred)
    else:
        assert not np.allclose(watching.yaws, 123.0)
        assert any(note.startswith("view: along the player's motion") for note in result.inferred)
