"""Smokes, fires and flashes in the fight (decoy_cli/sim/utility.py): each rule against the game's
numbers, through the combat step in a hand-made open room, and in a replay of a written round."""

from __future__ import annotations

from collections.abc import Iterator

import numpy as np
import pytest
from test_sim_combat import WithinTenMetres, _agents
from worlds import floor

from decoy_cli.csgo import HAMMER_TO_M
from decoy_cli.sim.combat import CombatStep, LineOfSight
from decoy_cli.sim.utility import (
    FIRE_HP_PER_S,
    FIRE_RADIUS_M,
    SMOKE_BLOCKS_M,
    SMOKE_CENTRE_UP_M,
    SMOKE_RADIUS_M,
    Utility,
)
from decoy_cli.world.physics import PhysicsWorld
from decoy_cli.world.world import World

T_FEET, CT_FEET = (0.0, 0.0, 0.0), (8.0, 0.0, 0.0)  # 8 m apart in the open: they see each other


@pytest.fixture(scope="module")
def physics() -> Iterator[PhysicsWorld]:
    world = World(floor(-20.0, -20.0, 20.0, 20.0), name="open room", source="hand-made")
    with PhysicsWorld(world) as lent:
        yield lent


def _smoke(x: float, y: float = 0.0, start: int = 0, end: int = 1000) -> Utility:
    """A smoke detonating on the floor at (x, y), active over [start, end)."""
    return Utility(
        smoke_at=np.array([[x, y, 0.0]]), smoke_start=np.array([start]), smoke_end=np.array([end])
    )


def _step(physics: PhysicsWorld, utility: Utility | None, tick: int = 30, **agent_kw):
    """Run one combat step between a T and a CT 8 m apart; the agents and the events."""
    agents = _agents(["T", "CT"], [T_FEET, CT_FEET], weapons=["AK-47", "M4A4"], **agent_kw)
    los = LineOfSight(physics, 2)
    try:
        step = CombatStep(los, WithinTenMetres(), "de_dust2", utility=utility)
        events = step.run(agents, tick, np.random.default_rng(0))
    finally:
        los.close()
    return agents, events


def test_a_smoke_between_two_players_hides_them_from_each_other(physics: PhysicsWorld) -> None:
    agents, _ = _step(physics, None)
    assert agents.hp.tolist() == [70, 70]  # without the smoke they trade shots
    agents, events = _step(physics, _smoke(4.0))
    assert agents.hp.tolist() == [100, 100] and events == []


def test_the_smoke_blocks_only_in_its_window_and_only_across_its_cloud(
    physics: PhysicsWorld,
) -> None:
    assert _step(physics, _smoke(4.0, start=60))[0].hp.tolist() == [70, 70]  # not yet
    assert _step(physics, _smoke(4.0, end=30))[0].hp.tolist() == [70, 70]  # over
    # a cloud beside the line: the chord through it is shorter than 70% of its radius
    beside = np.sqrt(SMOKE_RADIUS_M**2 - (SMOKE_BLOCKS_M / 2) ** 2) + 0.05
    assert _step(physics, _smoke(4.0, y=beside))[0].hp.tolist() == [70, 70]
    assert _step(physics, _smoke(4.0, y=beside - 0.1))[0].hp.tolist() == [100, 100]


def test_the_smoked_length_follows_the_games_sphere() -> None:
    """The chord through one cloud is 2 sqrt(r² - d²); an eye inside the cloud is blocked."""
    smoke = _smoke(0.0)
    centre_z = SMOKE_CENTRE_UP_M
    eyes_from = np.array([[-10.0, 0.0, centre_z], [-10.0, 3.0, centre_z], [-0.5, 0.0, centre_z]])
    eyes_to = np.array([[10.0, 0.0, centre_z], [10.0, 3.0, centre_z], [10.0, 5.0, centre_z]])
    blocked = smoke.sight_blocked(eyes_from, eyes_to, tick=10)
    assert blocked.tolist() == [True, False, True]
    assert pytest.approx(166 * HAMMER_TO_M) == SMOKE_RADIUS_M


def test_a_fire_burns_whoever_stands_in_it_at_the_measured_rate(physics: PhysicsWorld) -> None:
    fire = Utility(
        fire_at=np.array([[0.5, 0.0, 0.0]]), fire_start=np.array([0]), fire_end=np.array([100])
    )
    agents = _agents(["T", "CT"], [T_FEET, (30.0, 0.0, 0.0)])  # out of each other's reach
    los = LineOfSight(physics, 2)
    try:
        step = CombatStep(los, WithinTenMetres(), "de_dust2", utility=fire, step_s=0.5)
        events = step.run(agents, 30, np.random.default_rng(0))
        assert agents.hp.tolist() == [100 - FIRE_HP_PER_S * 0.5, 100]
        assert [(e.kind, e.agent) for e in events] == [("fire_damage", 0)]
        step.run(agents, 200, np.random.default_rng(0))  # the fire is out
        assert agents.hp[0] == 100 - FIRE_HP_PER_S * 0.5
        agents.position[0] = [0.5 + FIRE_RADIUS_M + 0.1, 0.0, 0.0]  # beside it
        step.run(agents, 60, np.random.default_rng(0))
        assert agents.hp[0] == 100 - FIRE_HP_PER_S * 0.5
    finally:
        los.close()


def test_a_fire_kills_when_the_fight_decides_deaths_and_stops_at_1_hp_otherwise(
    physics: PhysicsWorld,
) -> None:
    fire = Utility(
        fire_at=np.array([[0.0, 0.0, 0.0]]), fire_start=np.array([0]), fire_end=np.array([100])
    )
    for kills, hp, alive in ((True, 0, False), (False, 1, True)):
        agents = _agents(["T", "CT"], [T_FEET, (30.0, 0.0, 0.0)], hp=np.array([5, 100]))
        los = LineOfSight(physics, 2)
        try:
            step = CombatStep(los, WithinTenMetres(), "de_dust2", utility=fire, kills=kills)
            events = step.run(agents, 30, np.random.default_rng(0))
        finally:
            los.close()
        assert (int(agents.hp[0]), bool(agents.alive[0])) == (hp, alive)
        assert ("death" in [e.kind for e in events]) == (not alive)


def test_a_blind_player_does_not_shoot_but_can_be_shot(physics: PhysicsWorld) -> None:
    blind = Utility(blind_agent=np.array([0]), blind_start=np.array([0]), blind_end=np.array([60]))
    agents, _ = _step(physics, blind, tick=30)
    assert agents.hp.tolist() == [70, 100]  # the CT shot the blind T; the T fired nothing
    agents, _ = _step(physics, blind, tick=60)  # the blind is over
    assert agents.hp.tolist() == [70, 70]


def test_a_replay_heeds_the_rounds_smokes_and_names_them() -> None:
    """The sample's first round with a smoke over the middle of every real kill's line, for the
    whole round: the fight there hits less, and the replay counts the smokes it heeded."""
    from dataclasses import replace
    from pathlib import Path

    import pandas as pd

    from decoy_cli.damage import load_damage_model
    from decoy_cli.esta import read_match
    from decoy_cli.esta.reader import UTILITY_COLUMNS
    from decoy_cli.replay import ReplayOptions, replay_round
    from decoy_cli.waypoints.build import builtin_graph

    sample = Path(__file__).resolve().parents[1] / "examples" / "sample"
    round_ = read_match(next(sample.glob("*.json.xz"))).rounds[0]
    kills = round_.kills
    middle = (
        kills[["attackerX_m", "attackerY_m", "attackerZ_m"]].to_numpy()
        + kills[["victimX_m", "victimY_m", "victimZ_m"]].to_numpy()
    ) / 2
    smokes = pd.DataFrame(
        {
            "start_tick": round_.frame_ticks[0],
            "end_tick": round_.frame_ticks[-1] + 10_000,
            "start_s": -1.0,
            "end_s": 10_000.0,
            "x_m": middle[:, 0],
            "y_m": middle[:, 1],
            "z_m": middle[:, 2] - SMOKE_CENTRE_UP_M,  # the sphere's centre on the line
            "thrower_name": "T-1",
            "thrower_side": "T",
            "thrower_steamid": pd.array([11] * len(middle), dtype="Int64"),
        }
    )[list(UTILITY_COLUMNS)]
    smoked = replace(round_, smokes=smokes)
    graph = builtin_graph()
    options = ReplayOptions(damage_model=load_damage_model("rules"), seed=1)
    clear = replay_round(round_, graph, options)
    hidden = replay_round(smoked, graph, options)
    assert clear.utility is None
    assert hidden.utility == {"smokes": len(middle), "fires": 0, "blinds": 0}
    hits = [sum(e.kind == "damage" for e in r.events) for r in (clear, hidden)]
    assert hits[1] < hits[0]
