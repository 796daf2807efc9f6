"""The bomb in a replay follows the data (issue 12), on hand-made ESTA rounds (bomb_scenarios):
plants with and without bomb events, a late plant, an interrupted plant, a drop and pickup,
defuses with and without a kit, anomalies in the data, and the bomb table checked by hand."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from bomb_scenarios import (
    BombScenario,
    Player,
    frame_tick,
    hammer,
    site_a_walk,
    tick_of,
)
from typer.testing import CliRunner

from decoy_cli.cli import app
from decoy_cli.csgo import HAMMER_TO_M, TICK_RATE
from decoy_cli.esta import load_round
from decoy_cli.replay.replayer import ReplayOptions, ReplayResult, replay_round
from decoy_cli.waypoints.build import builtin_graph

ONE_TICK_S = 1 / TICK_RATE + 1e-6
"""The simulator's clock rounds a data time to its tick."""

PLANT_BEGIN_S = 8.0
PLANT_S = 11.05  # a real plant takes 3.05 s from plant_begin to plant


def carrier_round(frames: int = 40, plant_s: float | None = PLANT_S) -> tuple[BombScenario, Player]:
    """t1 walks into site A (one waypoint a frame), stands on the last waypoint and carries the
    bomb until the frame before `plant_s`; ct1 stands at the walk's start, far from the bomb."""
    walk, _ = site_a_walk()
    nodes = walk + [walk[-1]] * (frames - len(walk))
    planted_from = None
    if plant_s is not None:
        planted_from = next(j for j in range(frames) if frame_tick(j) >= tick_of(plant_s))
    t1 = Player(
        "t1",
        1,
        "T",
        nodes,
        has_bomb=[planted_from is None or j < planted_from for j in range(frames)],
    )
    ct1 = Player("ct1", 11, "CT", [walk[0]] * frames)
    scenario = BombScenario(frames, [t1, ct1], planted_from=planted_from)
    return scenario, t1


def replayed(scenario: BombScenario, tmp_path: Path, name: str = "round.json") -> ReplayResult:
    round_ = load_round(f"{scenario.write(tmp_path / name)}:1")
    options = ReplayOptions(combat=False, bomb=True, play_out=False)
    return replay_round(round_, builtin_graph(), options)


def kinds(result: ReplayResult, kind: str) -> list:
    return [e for e in result.events if e.kind == kind]


def test_a_plant_with_bomb_events_begins_at_plant_begin_and_takes_the_rules_time(
    tmp_path: Path,
) -> None:
    scenario, t1 = carrier_round()
    scenario.plant_tick = tick_of(PLANT_S)
    scenario.event(tick_of(PLANT_BEGIN_S), "plant_begin", t1)
    scenario.event(tick_of(PLANT_S), "plant", t1)
    result = replayed(scenario, tmp_path)
    (begin,), (plant,) = kinds(result, "plant_begin"), kinds(result, "plant")
    assert abs(begin.tick / TICK_RATE - PLANT_BEGIN_S) <= ONE_TICK_S
    assert plant.tick - begin.tick == 180  # 3.0 s at 60 Hz
    row = result.bomb_row()
    assert row is not None
    assert row["plant_data"] and row["plant_replay"]
    assert row["plant_time_error_s"] == pytest.approx(8.0 + 3.0 - PLANT_S, abs=ONE_TICK_S)
    assert row["plant_time_resolution_s"] == 0.0
    assert row["plant_site_data"] == row["plant_site_replay"] == "A"
    assert row["plant_position_error_m"] < 0.5
    assert row["bomb_anomalies"] == ""


def test_the_planter_is_on_time_at_every_target_it_stands_at_while_planting(
    tmp_path: Path,
) -> None:
    """Planting holds the carrier still where the real one stood planting: the targets of those
    seconds are reached as they come, not all at once when the plant completes."""
    scenario, t1 = carrier_round()
    scenario.plant_tick = tick_of(PLANT_S)
    scenario.event(tick_of(PLANT_BEGIN_S), "plant_begin", t1)
    scenario.event(tick_of(PLANT_S), "plant", t1)
    result = replayed(scenario, tmp_path)
    plan = result.plan.plans[0]
    during = (plan.target_seconds > PLANT_BEGIN_S) & (plan.target_seconds < PLANT_S)
    assert during.sum() >= 4  # frames every 0.5 s through the 3 s plant
    late = result.logs[0].lateness_s
    assert np.all(late[during] <= 1 / TICK_RATE + 1e-9)
    assert np.all(np.isfinite(late))
    assert result.lateness_table().iloc[0]["late_over_frame"] == 0


def test_a_planter_held_still_does_not_reach_a_target_elsewhere(tmp_path: Path) -> None:
    """The data has the planter a waypoint away during one frame of the plant (jitter): the
    replay's planter, held still, reaches that target only after the plant, late."""
    scenario, t1 = carrier_round()
    scenario.plant_tick = tick_of(PLANT_S)
    scenario.event(tick_of(PLANT_BEGIN_S), "plant_begin", t1)
    scenario.event(tick_of(PLANT_S), "plant", t1)
    walk, _ = site_a_walk()
    away = next(j for j in range(scenario.frames) if frame_tick(j) > tick_of(PLANT_BEGIN_S + 1.0))
    t1.nodes = [*t1.nodes[:away], walk[-2], *t1.nodes[away + 1 :]]
    result = replayed(scenario, tmp_path)
    plan, late = result.plan.plans[0], result.logs[0].lateness_s
    elsewhere = np.flatnonzero(plan.target_node != plan.target_node[-1])
    during = elsewhere[(plan.target_seconds[elsewhere] > PLANT_BEGIN_S)]
    assert len(during) == 1
    assert late[during[0]] > 1.0  # reached after the plant ended, not while held elsewhere


def test_a_plant_known_only_from_the_frames_is_the_first_planted_frame(tmp_path: Path) -> None:
    """The T-side files: no bomb events, `bombPlantTick` is the first frame showing the bomb
    planted (docs/metrics.md), known to the frame interval before it."""
    scenario, _ = carrier_round()
    result = replayed(scenario, tmp_path)
    planted_frame = scenario.planted_from
    assert planted_frame is not None
    data_s = (frame_tick(planted_frame) - 10_000) / 128
    assert result.bomb is not None and result.bomb.plant is not None
    assert result.bomb.plant.seconds == pytest.approx(data_s)
    assert result.bomb.plant.resolution_s == pytest.approx(0.5)
    assert result.bomb.plant.start_s == pytest.approx(data_s - 3.0)
    (plant,) = kinds(result, "plant")
    assert abs(plant.tick / TICK_RATE - data_s) <= ONE_TICK_S
    assert result.bomb_row()["plant_site_data"] == "A"  # type: ignore[index]


def test_a_late_plant_stops_the_round_clock(tmp_path: Path) -> None:
    """A plant completing 0.5 s before the 115 s round time: the replay plants too, and the
    round does not end by time."""
    frames = 240  # to 120 s
    scenario, t1 = carrier_round(frames, plant_s=114.5)
    scenario.plant_tick = tick_of(114.5)
    scenario.event(tick_of(111.45), "plant_begin", t1)
    scenario.event(tick_of(114.5), "plant", t1)
    result = replayed(scenario, tmp_path)
    assert len(kinds(result, "plant")) == 1
    assert result.outcome is None or result.outcome.reason != "TargetSaved"


def test_an_interrupted_plant_in_the_data_is_not_planted_early(tmp_path: Path) -> None:
    scenario, t1 = carrier_round(plant_s=12.05)
    scenario.plant_tick = tick_of(12.05)
    scenario.event(tick_of(7.5), "plant_begin", t1)
    scenario.event(tick_of(8.5), "plant_abort", t1)
    scenario.event(tick_of(9.0), "plant_begin", t1)
    scenario.event(tick_of(12.05), "plant", t1)
    result = replayed(scenario, tmp_path)
    begins, plants = kinds(result, "plant_begin"), kinds(result, "plant")
    assert len(begins) == len(plants) == 1
    assert abs(begins[0].tick / TICK_RATE - 9.0) <= ONE_TICK_S
    assert result.bomb_row()["plant_time_error_s"] == pytest.approx(-0.05, abs=ONE_TICK_S)  # type: ignore[index]


def test_the_bomb_is_dropped_and_picked_up_as_in_the_data(tmp_path: Path) -> None:
    """t1 lets the bomb go at frame 6 (it lies where the data shows it), t2, a frame behind on
    the same walk, picks it up at frame 10 and plants; t1 walking over it does not pick it up."""
    frames = 40
    walk, _ = site_a_walk()
    t1_nodes = walk + [walk[-1]] * (frames - len(walk))
    t2_nodes = [walk[0], *t1_nodes[:-1]]
    planted_from = 30
    t1 = Player("t1", 1, "T", t1_nodes, has_bomb=[j < 6 for j in range(frames)])
    t2 = Player("t2", 2, "T", t2_nodes, has_bomb=[10 <= j < planted_from for j in range(frames)])
    lies = hammer(walk[5])
    scenario = BombScenario(frames, [t1, t2], planted_from=planted_from)
    scenario.lying = dict.fromkeys(range(6, 10), lies)
    result = replayed(scenario, tmp_path)
    drops, pickups = kinds(result, "bomb_drop"), kinds(result, "bomb_pickup")
    assert [(e.agent, e.data.get("data")) for e in drops] == [(0, True)]
    assert drops[0].tick == round((frame_tick(6) - 10_000) / 128 * 60)
    assert np.allclose(drops[0].data["position"], np.array(lies) * HAMMER_TO_M)
    assert [e.agent for e in pickups] == [1]
    assert pickups[0].tick == round((frame_tick(10) - 10_000) / 128 * 60)
    (plant,) = kinds(result, "plant")
    assert plant.agent == 1


def defuse_round(kit: bool, defuse_s: float) -> BombScenario:
    """The plant of `carrier_round` with its events, then ct1 walks to the bomb (a waypoint
    from it), starts the defuse at 18.0 s and completes it after `defuse_s`."""
    frames = 70
    scenario, t1 = carrier_round(frames)
    scenario.plant_tick = tick_of(PLANT_S)
    scenario.event(tick_of(PLANT_BEGIN_S), "plant_begin", t1)
    scenario.event(tick_of(PLANT_S), "plant", t1)
    walk, _ = site_a_walk()
    t1.nodes = t1.nodes[:23] + [walk[-4]] * (frames - 23)  # steps back after the plant
    ct1 = scenario.players[1]
    ct1.kit = kit
    arrive = 22 + len(walk) - 2  # one waypoint a frame from frame 22
    ct1.nodes = [walk[0]] * 22 + walk[:-1] + [walk[-2]] * (frames - arrive - 1)
    scenario.event(tick_of(18.0), "defuse_start", ct1)
    scenario.event(tick_of(18.0 + defuse_s), "defuse", ct1)
    return scenario


@pytest.mark.parametrize(("kit", "defuse_s", "rules_s"), [(True, 5.02, 5.0), (False, 10.02, 10.0)])
def test_a_defuse_follows_the_data_with_or_without_a_kit(
    tmp_path: Path, kit: bool, defuse_s: float, rules_s: float
) -> None:
    result = replayed(defuse_round(kit, defuse_s), tmp_path)
    (start,), (done,) = kinds(result, "defuse_start"), kinds(result, "defuse")
    assert start.data["kit"] is kit
    assert abs(start.tick / TICK_RATE - 18.0) <= ONE_TICK_S
    assert (done.tick - start.tick) / TICK_RATE == pytest.approx(rules_s, abs=ONE_TICK_S)
    row = result.bomb_row()
    assert row is not None and row["defuse_data"] and row["defuse_replay"]
    assert row["defuse_time_error_s"] == pytest.approx(rules_s - defuse_s, abs=ONE_TICK_S)
    assert result.outcome is not None and result.outcome.reason == "BombDefused"
    # held still while defusing, the defuser reaches the targets it stands at as they come
    plan, late = result.plan.plans[1], result.logs[1].lateness_s
    during = (plan.target_seconds > 18.0) & (plan.target_seconds < done.tick / TICK_RATE)
    assert during.sum() >= 8
    assert np.all(late[during] <= 1 / TICK_RATE + 1e-9)


def test_anomalies_in_the_bomb_data_are_replayed_and_named(tmp_path: Path) -> None:
    # a plant by a player in no frame, with nobody carrying the bomb
    scenario, t1 = carrier_round(plant_s=None)
    t1.has_bomb = [False] * scenario.frames
    ghost = Player("ghost", 99, "T", t1.nodes)
    scenario.plant_tick = tick_of(PLANT_S)
    scenario.event(tick_of(PLANT_S), "plant", ghost)
    # a defuse logged before the plant, out of time order
    scenario.event(tick_of(5.0), "defuse_start", scenario.players[1])
    result = replayed(scenario, tmp_path)
    anomalies = result.bomb_row()["bomb_anomalies"]  # type: ignore[index]
    assert "out of time order" in anomalies
    assert "plant without a carrier" in anomalies
    assert not kinds(result, "plant")
    # a defuse of a bomb never planted, and a plant outside every site
    scenario, _ = carrier_round(plant_s=None)
    scenario.event(tick_of(6.0), "defuse_start", scenario.players[1])
    assert "never planted" in replayed(scenario, tmp_path, "b.json").bomb_row()["bomb_anomalies"]  # type: ignore[index]
    scenario, _ = carrier_round(plant_s=5.0)  # still on the walk, outside site A
    row = replayed(scenario, tmp_path, "c.json").bomb_row()
    assert row is not None and "outside every bomb-site zone" in row["bomb_anomalies"]
    assert row["plant_data"] and row["plant_site_data"] == ""
    # the replay's carrier can only plant inside a site: later, once it stands in A
    assert row["plant_site_replay"] == "A" and row["plant_time_error_s"] > 0


def test_the_bomb_table_of_evaluate_by_hand(tmp_path: Path) -> None:
    """Three rounds: a plant with events (replay 0.047 s early: 11.0 s against the data's tick
    at 11.047 s), a plant from frames only (on time), a defuse with a kit (planted like the
    first, defused 0.02 s early); the table's numbers follow by hand."""
    data = tmp_path / "data"
    data.mkdir()
    with_events, t1 = carrier_round()
    with_events.plant_tick = tick_of(PLANT_S)
    with_events.event(tick_of(PLANT_BEGIN_S), "plant_begin", t1)
    with_events.event(tick_of(PLANT_S), "plant", t1)
    frames_only, _ = carrier_round()
    for k, scenario in enumerate((with_events, frames_only, defuse_round(True, 5.02))):
        document = scenario.document()
        document["matchID"] = f"bomb-{k}"
        (data / f"m{k}.json").write_text(json.dumps(document))
    out = tmp_path / "out"
    result = CliRunner().invoke(
        app,
        ["evaluate", str(data), "--out", str(out), "--no-combat", "--workers", "1", "--no-figures"],
    )
    assert result.exit_code == 0, result.output
    table = pd.read_csv(out / "tables" / "bomb.csv").set_index("metric")
    assert table.loc["plant_agreement", "value"] == 1.0
    assert table.loc["plant_agreement", "rounds"] == 3
    early = (11.0 * 128 - (tick_of(PLANT_S) - 10_000)) / 128  # -0.047 s
    assert table.loc["plants_completed_share", "value"] == 1.0
    assert table.loc["plants_replay_only", "value"] == 0
    # signed errors: early, early, 0
    assert table.loc["plant_time_error_median_s", "value"] == pytest.approx(early, abs=ONE_TICK_S)
    assert table.loc["plant_time_error_mean_abs_s", "value"] == pytest.approx(
        -2 * early / 3, abs=ONE_TICK_S
    )
    assert table.loc["plant_site_agreement", "value"] == 1.0
    assert table.loc["defuse_agreement", "value"] == 1.0
    assert table.loc["defuse_time_error_median_s", "rounds"] == 1
    assert table.loc["defuse_time_error_median_s", "value"] == pytest.approx(-0.02, abs=ONE_TICK_S)
    confusion = pd.read_csv(out / "tables" / "bomb_plant_confusion.csv").set_index("data")
    assert confusion.loc["planted", "planted"] == 3 and confusion.loc["not planted"].sum() == 0
    report = (out / "report.md").read_text()
    assert "## The bomb" in report
    assert "| `plants_completed_share` | 1.000 |  | 3 |" in report  # 3 rounds: no interval
    assert "the bomb (3 rounds with bomb data)" in result.stdout
