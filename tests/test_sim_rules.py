"""Bomb and round rules: zones, plant, detonation, defuse, drop and pickup, every round end."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from decoy_cli.sim.rules import (
    BOMB_TARGET_BOXES,
    BombRules,
    RulesConfig,
    SiteZones,
    seconds_to_ticks,
)
from decoy_cli.sim.state import Agents, Bomb, BombStatus, SimEvent
from decoy_cli.waypoints.build import builtin_graph

DATA = Path(__file__).resolve().parents[1].parent / "shared" / "data"

# Site A: two waypoints on the floor at z = 0; site B: one waypoint 20 m east.
ZONES = SiteZones(nodes={"A": np.array([[0.0, 0.0, 0.0], [0.7, 0.0, 0.0]]), "B": [[20.0, 0, 0]]})
IN_A = (0.3, 0.2, 0.0)
OUTSIDE = (10.0, 0.0, 0.0)
BOMB_AT = np.array([0.0, 0.0, 0.0])


def make_agents(sides: list[str], positions: list, **kwargs) -> Agents:
    n = len(sides)
    return Agents.create(
        [f"p{i}" for i in range(n)], sides, np.asarray(positions, float), np.zeros(n), **kwargs
    )


class Round:
    """Agents, the bomb and the per-agent wishes, stepped one tick at a time like the engine."""

    def __init__(
        self,
        agents: Agents,
        carrier: int = -1,
        config: RulesConfig | None = None,
        bomb: Bomb | None = None,
    ) -> None:
        self.rules = BombRules(ZONES, config or RulesConfig())
        self.agents = agents
        self.bomb = bomb if bomb is not None else self.rules.start(agents, carrier)
        n = agents.count
        self.plant = np.zeros(n, bool)
        self.defuse = np.zeros(n, bool)
        self.moving = np.zeros(n, bool)
        self.tick = 0
        self.events: list[SimEvent] = []

    def step(self, ticks: int = 1) -> list[SimEvent]:
        new: list[SimEvent] = []
        for _ in range(ticks):
            self.tick += 1
            new += self.rules.step(
                self.tick, self.agents, self.bomb, self.plant, self.defuse, self.moving
            )
        self.events += new
        return new

    def kill(self, agent: int) -> list[SimEvent]:
        self.agents.alive[agent] = False
        self.agents.hp[agent] = 0
        new = self.rules.on_death(self.tick, agent, self.agents, self.bomb)
        self.events += new
        return new

    def outcome(self):
        return self.rules.outcome(self.tick, self.agents, self.bomb)


def kinds(events: list[SimEvent]) -> list[str]:
    return [e.kind for e in events]


def planted_round(
    ct_positions: list, has_defuser: list[bool] | None = None, planted_tick: int = 0
) -> Round:
    """One T far away and the given CTs, with the bomb planted on site A at `planted_tick`."""
    agents = make_agents(
        ["T"] + ["CT"] * len(ct_positions),
        [OUTSIDE, *ct_positions],
        has_defuser=np.array([False, *(has_defuser or [False] * len(ct_positions))]),
    )
    bomb = Bomb(
        status=BombStatus.PLANTED, position=BOMB_AT.copy(), site="A", planted_tick=planted_tick
    )
    rnd = Round(agents, bomb=bomb)
    rnd.tick = planted_tick
    return rnd


# ---- configuration ---------------------------------------------------------------------------


def test_durations_become_whole_ticks() -> None:
    cfg = RulesConfig()
    assert (cfg.round_ticks, cfg.plant_ticks, cfg.bomb_ticks) == (6900, 180, 2400)
    assert (cfg.defuse_ticks, cfg.defuse_kit_ticks) == (600, 300)
    assert 8.3 * 60 > 498  # float noise that must not add a tick
    assert seconds_to_ticks(8.3, 60) == 498
    assert seconds_to_ticks(3.21, 60) == 193  # rounded up, never shorter than the game
    assert RulesConfig(tick_rate=128, plant_s=3.2).plant_ticks == 410  # 409.6, rounded up


@pytest.mark.parametrize(
    "kwargs",
    [{"plant_s": 0.0}, {"round_time_s": -1.0}, {"defuse_s": float("nan")}, {"tick_rate": 60.0}],
)
def test_bad_config_is_refused(kwargs: dict) -> None:
    with pytest.raises(ValueError):
        RulesConfig(**kwargs)


# ---- zones -----------------------------------------------------------------------------------


def test_site_of_waypoint_zones() -> None:
    points = np.array(
        [
            [0.35, 0.0, 0.0],  # between the A waypoints
            [-0.75, 0.0, 0.0],  # exactly at the horizontal range
            [-0.76, 0.0, 0.0],
            [0.0, 0.0, 1.5],  # exactly at the vertical range
            [0.0, 0.0, -1.6],
            [20.5, 0.5, 1.0],
            OUTSIDE,
            [np.nan, 0.0, 0.0],
        ]
    )
    assert ZONES.site_of(points).tolist() == ["A", "A", "", "A", "", "B", "", ""]
    assert ZONES.site_of(np.array(IN_A)).tolist() == ["A"]
    with pytest.raises(ValueError):
        ZONES.site_of(np.zeros((2, 2)))


def test_site_of_boxes_and_site_order() -> None:
    zones = SiteZones(
        nodes={"B": [[0.0, 0.0, 0.0]]}, boxes={"A": ((-1.0, -1.0, -1.0), (1.0, 1.0, 1.0))}
    )
    # (0, 0, 0) is in both: the first site by name wins
    points = [[0, 0, 0], [0.9, 0.9, 0.9], [0.5, 0, 1.2], [1.1, 0, 0]]
    assert zones.site_of(points).tolist() == ["A", "A", "B", ""]
    with pytest.raises(ValueError):
        SiteZones(boxes={"A": ((1.0, 0.0, 0.0), (0.0, 1.0, 1.0))})
    with pytest.raises(ValueError):
        SiteZones(nodes={})


def test_zones_on_the_shipped_dust2_graph() -> None:
    graph = builtin_graph()
    t_spawn = graph.positions[graph.region_of("t_spawn")].mean(axis=0)
    ct_spawn = graph.positions[graph.region_of("ct_spawn")].mean(axis=0)
    # the nav-place site regions
    regions = SiteZones.from_graph(graph, boxes={})
    centroids = [
        graph.positions[graph.region_of(r)].mean(axis=0) for r in ("bombsite_a", "bombsite_b")
    ]
    assert regions.site_of(np.array([*centroids, t_spawn, ct_spawn])).tolist() == ["A", "B", "", ""]
    # the measured bomb-target boxes (the default on de_dust2)
    zones = SiteZones.from_graph(graph)
    boxes = BOMB_TARGET_BOXES["de_dust2"]
    centres = [np.add(*boxes[s]) / 2 for s in ("A", "B")]
    assert zones.site_of(np.array([*centres, t_spawn, ct_spawn])).tolist() == ["A", "B", "", ""]
    labels = zones.site_of(graph.positions)
    for site, region in (("A", "bombsite_a"), ("B", "bombsite_b")):
        # the simulated agents can plant: walkable waypoints lie in each zone
        assert np.sum(labels == site) >= 20
        # the game's zone is the core of the nav place, not all of it
        assert np.mean(labels[graph.region_of(region)] == site) < 0.6
    assert not np.any(labels[graph.region_of("t_spawn")] != "")


def test_real_plants_lie_in_the_logged_site() -> None:
    path = DATA / "esta_dust2_events" / "og-navi-blast2020-r01-18.json.xz"
    if not path.is_file():
        pytest.skip(f"real ESTA events not available at {path}")
    from decoy_cli.esta.reader import read_match

    zones = SiteZones.from_graph(builtin_graph())
    plants = [
        r.bomb_events[r.bomb_events["bombAction"].isin(["plant_begin", "plant"])]
        for r in read_match(path).rounds
    ]
    found = [row for table in plants for row in table.itertuples()]
    assert len(found) >= 10
    positions = np.array([[p.playerX_m, p.playerY_m, p.playerZ_m] for p in found])
    assert zones.site_of(positions).tolist() == [p.bombSite for p in found]


# ---- round start -----------------------------------------------------------------------------


def test_start_wants_an_alive_t_carrier() -> None:
    agents = make_agents(["T", "CT", "T"], [IN_A, IN_A, IN_A])
    agents.alive[2] = False
    rules = BombRules(ZONES)
    bomb = rules.start(agents, 0)
    assert (bomb.status, bomb.carrier) == (BombStatus.CARRIED, 0)
    np.testing.assert_array_equal(bomb.position, IN_A)
    for carrier in (1, 2, 3, -2):
        with pytest.raises(ValueError):
            rules.start(agents, carrier)
    assert rules.start(agents, -1).carrier == -1


def test_no_bomb_in_the_round() -> None:
    rnd = Round(make_agents(["T", "CT"], [IN_A, IN_A]), carrier=-1)
    rnd.plant[:] = True
    rnd.defuse[:] = True
    assert rnd.step(300) == []
    assert (rnd.bomb.status, rnd.bomb.carrier) == (BombStatus.CARRIED, -1)


# ---- plant -----------------------------------------------------------------------------------


def test_plant_takes_exactly_180_ticks() -> None:
    rnd = Round(make_agents(["T", "CT"], [IN_A, OUTSIDE]), carrier=0)
    rnd.plant[0] = True
    assert kinds(rnd.step()) == ["plant_begin"]
    assert rnd.events[0].data == {"site": "A"}
    begin = rnd.tick
    assert rnd.step(179) == []
    assert rnd.bomb.status == BombStatus.CARRIED and rnd.bomb.plant_ticks == 179
    (plant,) = rnd.step()
    assert (plant.kind, plant.agent, plant.tick - begin) == ("plant", 0, 180)
    bomb = rnd.bomb
    assert (bomb.status, bomb.site, bomb.planted_tick) == (BombStatus.PLANTED, "A", plant.tick)
    assert (bomb.carrier, bomb.planter) == (-1, -1)
    np.testing.assert_array_equal(bomb.position, IN_A)


def test_plant_outside_a_zone_is_refused() -> None:
    rnd = Round(make_agents(["T"], [OUTSIDE]), carrier=0)
    rnd.plant[0] = True
    assert rnd.step(400) == []
    assert rnd.bomb.status == BombStatus.CARRIED and rnd.bomb.planter == -1


def test_only_the_carrier_plants_and_only_standing_still() -> None:
    rnd = Round(make_agents(["T", "T"], [IN_A, IN_A]), carrier=0)
    rnd.plant[1] = True
    assert rnd.step(250) == []
    rnd.plant[0] = True
    rnd.moving[0] = True
    assert rnd.step(250) == []
    assert rnd.bomb.status == BombStatus.CARRIED


def test_plant_aborted_by_moving_restarts_from_zero() -> None:
    rnd = Round(make_agents(["T"], [IN_A]), carrier=0)
    rnd.plant[0] = True
    rnd.step(100)
    rnd.moving[0] = True
    (abort,) = rnd.step()
    assert (abort.kind, abort.data) == ("plant_abort", {"reason": "moved"})
    rnd.moving[0] = False
    assert kinds(rnd.step()) == ["plant_begin"]
    begin = rnd.tick
    rnd.step(179)
    assert rnd.bomb.status == BombStatus.CARRIED
    assert kinds(rnd.step()) == ["plant"] and rnd.tick - begin == 180


def test_plant_aborted_by_stopping_and_by_leaving_the_zone() -> None:
    rnd = Round(make_agents(["T"], [IN_A]), carrier=0)
    rnd.plant[0] = True
    rnd.step(10)
    rnd.plant[0] = False
    assert [e.data["reason"] for e in rnd.step()] == ["stopped"]
    rnd.plant[0] = True
    rnd.step(10)
    rnd.agents.position[0] = OUTSIDE
    assert [e.data["reason"] for e in rnd.step()] == ["left_zone"]
    assert rnd.bomb.plant_ticks == 0 and rnd.bomb.planter == -1


def test_planter_death_aborts_and_drops_the_bomb() -> None:
    rnd = Round(make_agents(["T", "CT"], [IN_A, OUTSIDE]), carrier=0)
    rnd.plant[0] = True
    rnd.step(50)
    events = rnd.kill(0)
    assert kinds(events) == ["plant_abort", "bomb_drop"]
    assert events[0].data == {"reason": "died"}
    assert rnd.bomb.status == BombStatus.DROPPED
    np.testing.assert_array_equal(rnd.bomb.position, IN_A)


# ---- detonation ------------------------------------------------------------------------------


def test_bomb_explodes_exactly_40_s_after_the_plant() -> None:
    rnd = Round(make_agents(["T", "CT"], [IN_A, OUTSIDE]), carrier=0)
    rnd.plant[0] = True
    rnd.step(181)
    planted = rnd.bomb.planted_tick
    rnd.plant[0] = False
    rnd.step(2399)
    assert rnd.bomb.status == BombStatus.PLANTED and rnd.outcome() is None
    (explode,) = rnd.step()
    assert (explode.kind, explode.tick - planted, explode.data) == ("explode", 2400, {"site": "A"})
    outcome = rnd.outcome()
    assert (outcome.winner, outcome.reason, outcome.tick) == ("T", "TargetBombed", explode.tick)


# ---- defuse ----------------------------------------------------------------------------------


@pytest.mark.parametrize(("kit", "ticks"), [(True, 300), (False, 600)])
def test_defuse_takes_5_s_with_a_kit_and_10_s_without(kit: bool, ticks: int) -> None:
    rnd = planted_round([(1.0, 1.0, 0.5)], has_defuser=[kit])
    rnd.defuse[1] = True
    (start,) = rnd.step()
    assert (start.kind, start.agent, start.data) == ("defuse_start", 1, {"site": "A", "kit": kit})
    rnd.step(ticks - 1)
    assert rnd.bomb.status == BombStatus.PLANTED and rnd.outcome() is None
    (defuse,) = rnd.step()
    assert (defuse.kind, defuse.tick - start.tick) == ("defuse", ticks)
    assert rnd.bomb.status == BombStatus.DEFUSED
    outcome = rnd.outcome()
    assert (outcome.winner, outcome.reason) == ("CT", "BombDefused")


def test_defuse_needs_range_and_a_ct() -> None:
    rnd = planted_round([(1.6, 0.0, 0.0), (0.0, 0.0, 1.1)])  # too far, too high
    rnd.agents.position[0] = BOMB_AT  # a T on the bomb
    rnd.defuse[:] = True
    assert rnd.step(700) == []


def test_defuse_aborted_by_death() -> None:
    rnd = planted_round([(0.5, 0.0, 0.0)])
    rnd.defuse[1] = True
    rnd.step(200)
    events = rnd.kill(1)
    assert kinds(events) == ["defuse_aborted"] and events[0].data == {"reason": "died"}
    assert rnd.bomb.defuser == -1 and rnd.bomb.defuse_ticks == 0
    assert rnd.step(500) == []


@pytest.mark.parametrize("cause", ["moved", "out_of_range", "stopped"])
def test_defuse_aborted_and_restarted_from_zero(cause: str) -> None:
    rnd = planted_round([(0.5, 0.0, 0.0)], has_defuser=[True])
    rnd.defuse[1] = True
    rnd.step(250)
    if cause == "moved":
        rnd.moving[1] = True
    elif cause == "out_of_range":
        rnd.agents.position[1] = (3.0, 0.0, 0.0)
    else:
        rnd.defuse[1] = False
    (abort,) = rnd.step()
    assert (abort.kind, abort.agent, abort.data) == ("defuse_aborted", 1, {"reason": cause})
    rnd.moving[1] = False
    rnd.defuse[1] = True
    rnd.agents.position[1] = (0.5, 0.0, 0.0)
    (start,) = rnd.step()
    rnd.step(299)
    assert rnd.bomb.status == BombStatus.PLANTED
    assert kinds(rnd.step()) == ["defuse"] and rnd.tick - start.tick == 300


def test_one_defuser_at_a_time() -> None:
    rnd = planted_round([(0.5, 0.0, 0.0), (0.0, 0.5, 0.0)], has_defuser=[False, True])
    rnd.defuse[1:] = True
    assert [(e.kind, e.agent) for e in rnd.step()] == [("defuse_start", 1)]
    rnd.step(400)  # agent 2's kit does not speed up agent 1's defuse
    assert rnd.bomb.defuser == 1 and rnd.bomb.status == BombStatus.PLANTED
    rnd.defuse[1] = False
    assert [(e.kind, e.agent) for e in rnd.step()] == [("defuse_aborted", 1), ("defuse_start", 2)]


def test_bomb_explodes_before_a_late_defuse() -> None:
    # 600 ticks of defuse started 600 ticks before the detonation: it would end on the
    # detonation tick, and the detonation comes first
    rnd = planted_round([(0.5, 0.0, 0.0)], planted_tick=1000)
    rnd.step(2400 - 600 - 1)
    rnd.defuse[1] = True
    (start,) = rnd.step()
    assert start.kind == "defuse_start" and start.tick == 1000 + 2400 - 600
    rnd.step(599)
    assert rnd.bomb.status == BombStatus.PLANTED
    (explode,) = rnd.step()
    assert (explode.kind, explode.tick, explode.data["defuser"]) == ("explode", 3400, 1)
    assert rnd.bomb.status == BombStatus.EXPLODED and rnd.bomb.defuser == -1
    assert rnd.outcome().reason == "TargetBombed"
    assert rnd.step(10) == []


# ---- drop and pickup -------------------------------------------------------------------------


def test_carrier_death_drops_the_bomb_where_it_stood() -> None:
    rnd = Round(make_agents(["T", "T"], [(5.0, 5.0, 1.0), OUTSIDE]), carrier=0)
    rnd.agents.position[0] = (6.0, 5.0, 1.0)
    rnd.step()
    (drop,) = rnd.kill(0)
    assert (drop.kind, drop.agent, drop.data) == ("bomb_drop", 0, {"position": [6.0, 5.0, 1.0]})
    assert (rnd.bomb.status, rnd.bomb.carrier) == (BombStatus.DROPPED, -1)
    np.testing.assert_array_equal(rnd.bomb.position, (6.0, 5.0, 1.0))
    assert rnd.kill(0) == []  # a second call changes nothing


def test_a_dead_carrier_found_by_step_drops_the_bomb() -> None:
    rnd = Round(make_agents(["T"], [(5.0, 5.0, 1.0)]), carrier=0)
    rnd.agents.alive[0] = False
    assert kinds(rnd.step()) == ["bomb_drop"]
    assert rnd.bomb.status == BombStatus.DROPPED


def test_dropped_bomb_is_picked_up_by_a_t_not_a_ct() -> None:
    drop_at = (5.0, 5.0, 1.0)
    agents = make_agents(
        ["T", "CT", "T", "T", "T"],
        [drop_at, drop_at, (5.85, 5.0, 1.0), (5.0, 5.0, 2.1), OUTSIDE],
    )
    rnd = Round(agents, carrier=0)
    rnd.kill(0)
    # a CT on it, a T 0.85 m away, a T 1.1 m above: nobody picks it up
    assert rnd.step(60) == []
    rnd.agents.position[4] = (5.5, 5.3, 1.5)  # 0.58 m away, 0.5 m above
    rnd.agents.position[3] = (5.7, 5.0, 1.0)  # 0.7 m away: lower index than 4
    (pickup,) = rnd.step()
    assert (pickup.kind, pickup.agent) == ("bomb_pickup", 3)
    assert (rnd.bomb.status, rnd.bomb.carrier) == (BombStatus.CARRIED, 3)
    rnd.agents.position[3] = IN_A
    rnd.step()
    np.testing.assert_array_equal(rnd.bomb.position, IN_A)  # follows its new carrier


def test_dead_t_does_not_pick_up() -> None:
    rnd = Round(make_agents(["T", "T"], [(5.0, 5.0, 1.0), (5.0, 5.0, 1.0)]), carrier=0)
    rnd.kill(1)
    rnd.kill(0)
    assert rnd.step(10) == [] and rnd.bomb.status == BombStatus.DROPPED


# ---- round end -------------------------------------------------------------------------------


def test_time_runs_out_at_exactly_115_s() -> None:
    rnd = Round(make_agents(["T", "CT"], [OUTSIDE, OUTSIDE]), carrier=0)
    rnd.tick = 6899
    assert rnd.outcome() is None
    rnd.tick = 6900
    outcome = rnd.outcome()
    assert (outcome.winner, outcome.reason, outcome.tick) == ("CT", "TargetSaved", 6900)


def test_a_plant_stops_the_round_clock() -> None:
    rnd = Round(make_agents(["T", "CT"], [IN_A, OUTSIDE]), carrier=0)
    rnd.tick = 6700
    rnd.plant[0] = True
    rnd.step(181)  # planted at tick 6881
    assert rnd.bomb.status == BombStatus.PLANTED
    rnd.step(2000)  # well past 115 s
    assert rnd.outcome() is None
    assert rnd.bomb.planted_tick == 6881
    rnd.step(400)
    assert rnd.outcome().reason == "TargetBombed" and rnd.tick == 6881 + 2400


def test_elimination_before_a_plant() -> None:
    rnd = Round(make_agents(["T", "T", "CT"], [OUTSIDE] * 3), carrier=0)
    rnd.kill(0)
    assert rnd.outcome() is None
    rnd.kill(1)
    outcome = rnd.outcome()
    assert (outcome.winner, outcome.reason) == ("CT", "CTWin")
    rnd = Round(make_agents(["T", "CT", "CT"], [OUTSIDE] * 3), carrier=0)
    rnd.kill(1)
    rnd.kill(2)
    outcome = rnd.outcome()
    assert (outcome.winner, outcome.reason) == ("T", "TerroristsWin")


def test_elimination_after_a_plant() -> None:
    rnd = planted_round([(0.5, 0.0, 0.0)], planted_tick=7000)
    rnd.kill(0)  # the last T: the round goes on, the CT may defuse
    assert rnd.outcome() is None
    rnd.kill(1)
    outcome = rnd.outcome()
    assert (outcome.winner, outcome.reason) == ("T", "TerroristsWin")
    rnd = planted_round([(0.5, 0.0, 0.0)])
    rnd.kill(1)  # all CT dead after the plant
    assert rnd.outcome().reason == "TerroristsWin"


def test_both_sides_eliminated_on_the_same_tick() -> None:
    rnd = Round(make_agents(["T", "CT"], [OUTSIDE, OUTSIDE]), carrier=0)
    rnd.kill(0)
    rnd.kill(1)
    assert rnd.outcome().reason == "CTWin"
    rnd = planted_round([(0.5, 0.0, 0.0)])
    rnd.kill(0)
    rnd.kill(1)
    assert rnd.outcome().reason == "TerroristsWin"


def test_t_only_round() -> None:
    rnd = Round(make_agents(["T", "T"], [IN_A, OUTSIDE]), carrier=0)
    assert rnd.outcome() is None  # no CT is not "all CT dead"
    rnd.tick = 6900
    assert rnd.outcome().reason == "TargetSaved"
    rnd = Round(make_agents(["T", "T"], [IN_A, OUTSIDE]), carrier=0)
    rnd.plant[0] = True
    rnd.step(181)
    rnd.kill(0)
    rnd.kill(1)
    assert rnd.outcome() is None  # planted: on to the detonation
    rnd.step(2400)
    assert rnd.outcome().reason == "TargetBombed"
    rnd = Round(make_agents(["T"], [OUTSIDE]), carrier=0)
    rnd.kill(0)
    assert rnd.outcome().reason == "CTWin"


def test_ct_only_and_empty_rounds() -> None:
    rnd = Round(make_agents(["CT"], [OUTSIDE]))
    assert rnd.outcome() is None
    rnd.kill(0)
    assert rnd.outcome().reason == "TerroristsWin"
    rnd = Round(make_agents([], np.zeros((0, 3))))
    assert rnd.outcome() is None and rnd.step(10) == []
    rnd.tick = 6900
    assert rnd.outcome().reason == "TargetSaved"


def test_bomb_disabled_mode() -> None:
    config = RulesConfig(bomb_enabled=False)
    rnd = Round(make_agents(["T", "CT"], [IN_A, IN_A]), carrier=0, config=config)
    assert rnd.bomb.carrier == -1  # the carrier is ignored
    rnd.plant[:] = True
    rnd.defuse[:] = True
    assert rnd.step(300) == []
    assert rnd.kill(0) == []
    assert rnd.outcome().reason == "CTWin"
    rnd = Round(make_agents(["T", "CT"], [IN_A, IN_A]), config=config)
    # even a planted bomb is ignored: the clock runs, elimination decides
    rnd.bomb = Bomb(status=BombStatus.PLANTED, position=BOMB_AT.copy(), site="A", planted_tick=0)
    rnd.tick = 6900
    assert rnd.outcome().reason == "TargetSaved"
    rnd.kill(1)
    assert rnd.outcome().reason == "TerroristsWin"
