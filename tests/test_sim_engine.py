"""The simulator's tick loop (`decoy_cli.sim.engine.Simulator`) on a hand-made line of waypoints,
with a scripted policy and a fake combat step: when agents are asked for decisions, when combat
runs, what is recorded, kills, invalid moves and how a round ends.

Every expected tick is derived from the rules, not from a previous run:

* the graph is a straight line of nodes 1 m apart (`LINE`), so an edge at 3 m/s takes exactly
  20 ticks at 60 Hz, at 6 m/s 10 ticks; the knife's CS:GO top speed is 250 u/s = 4.7625 m/s,
  so a 1 m edge at the capped speed takes ceil(60 / 4.7625) = 13 ticks;
* an agent decided at tick t moves during tick t, so a D-tick edge arrives at t + D - 1 and the
  agent is asked again at t + D; a STOP of h ticks decided at t is asked again at t + h;
* the round here lasts 2 s = 120 ticks (`ROUND_TICKS`) and ends "TargetSaved" (CT) at tick 120.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from decoy_cli.csgo import TICK_RATE
from decoy_cli.sim.engine import Decision, Simulator
from decoy_cli.sim.movement import KinematicMover
from decoy_cli.sim.rules import BombRules, RulesConfig, SiteZones
from decoy_cli.sim.setup import RoundSetup, open_round
from decoy_cli.sim.state import Agents, BombStatus, RoundOutcome, SimEvent
from decoy_cli.waypoints.graph import STOP_ACTION, EdgeKind, WaypointGraph
from decoy_cli.weapons import NO_WEAPON, max_speed_m_s

E, W = 2, 6  # compass directions east and west
NODES = 6
"""`LINE` has nodes 0..5 at x = 0, 1, ..., 5 m (y = z = 0), joined east and west."""
ROUND_S = 2.0
ROUND_TICKS = 120  # 2 s at 60 Hz
WALK_3 = 20  # ticks to cross a 1 m edge at 3 m/s
WALK_6 = 10  # ... at 6 m/s
WALK_KNIFE = 13  # ... at the knife's 4.7625 m/s: 12 ticks cover 0.9525 m, the 13th arrives
FOREVER = 10**6


def line_graph() -> WaypointGraph:
    edges = [(i, i + 1, E) for i in range(NODES - 1)] + [(i + 1, i, W) for i in range(NODES - 1)]
    e = np.array(edges, dtype=np.int64)
    return WaypointGraph(
        positions=np.array([(float(i), 0.0, 0.0) for i in range(NODES)]),
        edge_source=e[:, 0].astype(np.int32),
        edge_target=e[:, 1].astype(np.int32),
        edge_kind=np.full(len(e), EdgeKind.WALK, dtype=np.uint8),
        edge_direction=e[:, 2].astype(np.uint8),
        node_place=np.full(NODES, -1, dtype=np.int16),
        place_names=[],
        regions={},
    )


LINE = line_graph()
# The only bomb site lies 30 m east of the line: nobody can plant in these rounds.
RULES = BombRules(SiteZones(nodes={"A": [[30.0, 0.0, 0.0]]}), RulesConfig(round_time_s=ROUND_S))


def stop(hold: int = FOREVER) -> Decision:
    return Decision(STOP_ACTION, hold_ticks=hold)


def walk(direction: int, speed: float | None = 3.0, **kwargs) -> Decision:
    return Decision(direction, speed=speed, **kwargs)


class Script:
    """A policy that plays each agent's list of decisions in order (then STOP for good) and
    records every (tick, agent) it was asked at."""

    def __init__(self, plans: dict[int, list[Decision]] | None = None) -> None:
        self.plans = {a: list(p) for a, p in (plans or {}).items()}
        self.asked: list[tuple[int, int]] = []

    def decide(self, sim: Simulator, agent: int) -> Decision:
        self.asked.append((sim.tick, agent))
        plan = self.plans.get(agent, [])
        return plan.pop(0) if plan else stop()

    def ticks_of(self, agent: int) -> list[int]:
        return [t for t, a in self.asked if a == agent]


class FakeCombat:
    """A combat step that records the ticks it ran at; `kills` maps a tick to (attacker,
    victim) pairs it kills then, as the real step does (alive False, hp 0, a "kill" event)."""

    def __init__(self, kills: dict[int, list[tuple[int, int]]] | None = None) -> None:
        self.kills = kills or {}
        self.ticks: list[int] = []
        self.rngs: list[np.random.Generator] = []

    def run(self, agents: Agents, tick: int, rng: np.random.Generator) -> list[SimEvent]:
        self.ticks.append(tick)
        self.rngs.append(rng)
        events = []
        for attacker, victim in self.kills.get(tick, []):
            agents.alive[victim] = False
            agents.hp[victim] = 0
            events.append(SimEvent(tick, "kill", attacker, victim))
        return events


def make_agents(sides: list[str], nodes: list[int], **kwargs) -> Agents:
    names = [f"p{i}" for i in range(len(sides))]
    return Agents.create(names, sides, LINE.positions[nodes], np.array(nodes), **kwargs)


def make_sim(
    agents: Agents,
    policy: Script | None = None,
    combat: FakeCombat | None = None,
    every: int = 30,
    **kwargs,
) -> Simulator:
    """The one place that builds a Simulator for these tests (combat None: nobody shoots)."""
    return Simulator(
        LINE,
        agents,
        KinematicMover(),
        policy or Script(),
        RULES,
        combat=combat,
        combat_every_ticks=every,
        seed=0,
        **kwargs,
    )


def t_and_ct() -> Agents:
    """A T on node 0 and a CT on node 5."""
    return make_agents(["T", "CT"], [0, 5])


# ---- the round's clock -----------------------------------------------------------------------


def test_the_test_constants_follow_the_rules() -> None:
    assert RULES.config.round_ticks == ROUND_TICKS
    knife = 250 * 0.01905  # CS:GO's knife speed, 250 u/s, in m/s
    assert max_speed_m_s("Knife") == pytest.approx(knife)
    assert np.ceil(60 / knife) == WALK_KNIFE
    assert (WALK_3, WALK_6) == (60 / 3.0, 60 / 6.0)


def test_a_round_nobody_wins_ends_target_saved_at_the_time_limit() -> None:
    sim = make_sim(t_and_ct())
    sim.run(to_tick=ROUND_TICKS - 1)
    assert not sim.done and sim.outcome is None
    assert sim.needs_decision.tolist() == [False, False]  # both stand in a STOP for good
    sim.run()
    assert sim.done
    assert sim.tick == ROUND_TICKS
    assert sim.outcome == RoundOutcome("CT", "TargetSaved", ROUND_TICKS)
    assert sim.events == [
        SimEvent(ROUND_TICKS, "round_end", data={"winner": "CT", "reason": "TargetSaved"})
    ]
    # a finished round does not move on
    assert sim.step() == []
    assert sim.tick == ROUND_TICKS
    assert sim.needs_decision.tolist() == [False, False]


def test_a_late_start_still_ends_on_the_round_clock() -> None:
    sim = make_sim(t_and_ct(), start_tick=10)
    sim.run()
    assert (sim.tick, sim.outcome) == (ROUND_TICKS, RoundOutcome("CT", "TargetSaved", ROUND_TICKS))


def test_a_combat_step_more_often_than_every_tick_is_refused() -> None:
    with pytest.raises(ValueError, match="combat_every_ticks"):
        make_sim(t_and_ct(), combat=FakeCombat(), every=0)


# ---- combat cadence --------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("every", "start", "expected"),
    [
        (30, 0, [30, 60, 90, 120]),
        (7, 0, [7 * k for k in range(1, 18)]),  # 7 * 17 = 119, the last before 120
        (30, 45, [60, 90, 120]),  # by the tick count, not by ticks since the start tick
    ],
)
def test_combat_runs_every_combat_every_ticks(every: int, start: int, expected: list[int]) -> None:
    combat = FakeCombat()
    sim = make_sim(t_and_ct(), combat=combat, every=every, start_tick=start)
    sim.run()
    assert sim.tick == ROUND_TICKS
    assert combat.ticks == expected
    assert all(rng is sim.rng for rng in combat.rngs)  # the simulator's seeded generator


def test_no_combat_when_it_is_switched_off() -> None:
    """`RoundSetup(combat=False)` with a damage model: no combat step at all, nobody dies."""

    def lethal(batch, rng):  # would kill at once; must never be called
        raise AssertionError("the damage model was called with combat off")

    setup = RoundSetup(
        graph=LINE, combat=False, damage_model=lethal, rules=RULES.config, zones=RULES.zones
    )
    assert not setup.shooting and not setup.needs_physics
    with open_round(setup, t_and_ct(), Script(), seed=0) as sim:
        sim.run()
    assert sim.combat is None
    assert sim.agents.alive.tolist() == [True, True]
    assert sim.outcome == RoundOutcome("CT", "TargetSaved", ROUND_TICKS)


@pytest.mark.parametrize(
    ("attacker", "victim", "winner", "reason", "kinds"),
    [
        (0, 1, "T", "TerroristsWin", ["kill", "round_end"]),  # the only CT dies
        (1, 0, "CT", "CTWin", ["kill", "bomb_drop", "round_end"]),  # the only T, the carrier
    ],
)
def test_a_combat_kill_ends_the_round_by_elimination(
    attacker: int, victim: int, winner: str, reason: str, kinds: list[str]
) -> None:
    combat = FakeCombat(kills={60: [(attacker, victim)]})
    # the T walks east at 3 m/s the whole round: it is at x = 60 * 0.05 = 3 m at tick 60
    policy = Script({0: [walk(E)] * 5})
    sim = make_sim(t_and_ct(), policy=policy, combat=combat, bomb_carrier=0)
    sim.run()
    assert combat.ticks == [30, 60]
    assert (sim.tick, sim.outcome) == (60, RoundOutcome(winner, reason, 60))
    assert [e.kind for e in sim.events] == kinds
    assert all(e.tick == 60 for e in sim.events)
    assert sim.events[0] == SimEvent(60, "kill", attacker, victim)
    assert sim.events[-1].data == {"winner": winner, "reason": reason}
    assert sim.agents.alive.tolist() == [victim != 0, victim != 1]
    np.testing.assert_allclose(sim.agents.position[0], [3.0, 0.0, 0.0], atol=1e-9)
    if victim == 0:
        assert sim.bomb.status == BombStatus.DROPPED
        np.testing.assert_allclose(sim.bomb.position, [3.0, 0.0, 0.0], atol=1e-9)


def test_a_combat_kill_of_one_of_two_ct_goes_on() -> None:
    combat = FakeCombat(kills={30: [(0, 1)]})
    agents = make_agents(["T", "CT", "CT"], [0, 4, 5])
    policy = Script({1: [stop(40)]})  # asked at 1 (STOP until 41); dead at 30: never again
    sim = make_sim(agents, policy=policy, combat=combat)
    sim.run()
    assert sim.outcome == RoundOutcome("CT", "TargetSaved", ROUND_TICKS)
    assert policy.ticks_of(1) == [1]
    assert [(e.tick, e.kind) for e in sim.events] == [(30, "kill"), (ROUND_TICKS, "round_end")]


# ---- decisions -------------------------------------------------------------------------------


def test_agents_are_asked_exactly_when_they_arrive_or_their_stop_ends() -> None:
    agents = make_agents(["T", "CT", "T"], [0, 4, 2])
    agents.alive[2] = False  # dead from the start
    agents.hp[2] = 0
    policy = Script(
        {
            0: [
                walk(E),  # 1: node 0 -> 1 in 20 ticks, arrives at 20
                stop(10),  # 21: until 31
                walk(E),  # 31: node 1 -> 2, arrives at 50
                walk(W, speed=6.0, max_speed=6.0),  # 51: the cap raised above the knife's: 10
            ],
            1: [
                stop(25),  # 1: until 26
                stop(1),  # 26: one tick
                stop(0),  # 27: a STOP lasts at least one tick
                walk(E, speed=10.0),  # 28: capped at the knife's speed, 13 ticks, arrives at 40
            ],
            2: [walk(E)],
        }
    )
    sim = make_sim(agents, policy=policy)
    expected = {0: [1, 21, 31, 51, 61], 1: [1, 26, 27, 28, 41], 2: []}
    due: list[tuple[int, int]] = []
    while not sim.done:
        due += [(sim.tick + 1, int(a)) for a in np.flatnonzero(sim.needs_decision)]
        sim.step()
        if sim.tick == 40:
            # agent 0 is halfway from node 1 to node 2; agent 1 has just reached node 5
            assert sim.agents.node.tolist() == [1, 5, 2]
            assert sim.agents.position[1].tolist() == [5.0, 0.0, 0.0]
            np.testing.assert_allclose(sim.agents.position[0], [1.5, 0.0, 0.0], atol=1e-9)
        if sim.tick == 60:
            assert sim.agents.node[0] == 1
            np.testing.assert_allclose(sim.agents.position[0], [1.0, 0.0, 0.0], atol=1e-9)
    assert {a: policy.ticks_of(a) for a in range(3)} == expected
    assert due == policy.asked  # needs_decision names exactly who is asked at the next tick
    assert sim.state.decisions.tolist() == [5, 5, 0]
    assert sim.agents.position[2].tolist() == [2.0, 0.0, 0.0]


def test_an_agent_between_waypoints_is_not_asked() -> None:
    policy = Script({0: [walk(E)]})
    sim = make_sim(t_and_ct(), policy=policy)
    for tick in range(1, WALK_3 + 1):
        sim.step()
        assert sim.needs_decision[0] == (tick == WALK_3)  # it arrives at tick 20
        assert sim.agents.node[0] == (1 if tick == WALK_3 else 0)
        np.testing.assert_allclose(sim.agents.position[0], [0.05 * tick, 0.0, 0.0], atol=1e-9)
    sim.step()
    assert policy.ticks_of(0) == [1, WALK_3 + 1]


def test_an_impossible_move_holds_and_is_recorded() -> None:
    # node 0 is the west end of the line: there is no edge west
    policy = Script({0: [walk(W, hold_ticks=15)]})
    sim = make_sim(t_and_ct(), policy=policy)
    sim.run(to_tick=16)
    assert sim.events == [SimEvent(1, "invalid_action", 0, data={"action": W})]
    assert policy.ticks_of(0) == [1, 16]
    assert sim.agents.position[0].tolist() == [0.0, 0.0, 0.0]
    assert sim.agents.node[0] == 0


@pytest.mark.parametrize(
    ("decision", "why"),
    [
        (walk(E, speed=float("nan")), "cannot move at a speed"),
        (walk(E, max_speed=-1.0), "cannot move at a speed"),
        (Decision(9), "has no such action"),
    ],
)
def test_a_decision_the_round_cannot_take_is_an_error(decision: Decision, why: str) -> None:
    sim = make_sim(t_and_ct(), policy=Script({0: [decision]}))
    with pytest.raises(ValueError, match=f"agent 0 {why}"):
        sim.step()


class RelocatesFirst(Script):
    """Puts agent 0 on node 3 at its first decision (as a replay crosses a graph gap)."""

    def decide(self, sim: Simulator, agent: int) -> Decision:
        if agent == 0 and not self.asked:
            sim.relocate(0, 3)
        return super().decide(sim, agent)


def test_a_relocation_inside_a_decision_moves_on_from_the_new_node() -> None:
    policy = RelocatesFirst({0: [walk(E)]})  # from node 3 (after the relocation) to node 4
    sim = make_sim(t_and_ct(), policy=policy)
    sim.run(to_tick=WALK_3 + 1)
    assert sim.events == [SimEvent(1, "relocate", 0, data={"node": 3})]
    assert policy.ticks_of(0) == [1, WALK_3 + 1]
    assert sim.agents.node[0] == 4
    np.testing.assert_allclose(sim.agents.position[0], [4.0, 0.0, 0.0], atol=1e-9)


def test_equipment_changed_from_outside_is_held_and_paces_the_next_moves() -> None:
    # at full speed a 1 m edge takes ceil(60 / 3.81) = 16 ticks with an AWP (200 u/s), 13 with
    # the empty hand (the knife's speed)
    awp = math.ceil(TICK_RATE / max_speed_m_s("AWP"))
    policy = Script({0: [walk(E, speed=None), walk(E, speed=None)]})
    sim = make_sim(t_and_ct(), policy=policy)
    sim.equip(0, weapon="AWP", has_defuser=True)
    assert sim.agents.weapon[0] == "AWP" and sim.agents.has_defuser[0]
    sim.run(to_tick=awp)
    sim.disarm(0)
    sim.run(to_tick=awp + WALK_KNIFE + 1)
    assert policy.ticks_of(0) == [1, 1 + awp, 1 + awp + WALK_KNIFE]
    assert sim.agents.weapon[0] == NO_WEAPON and sim.agents.has_defuser[0]


# ---- kills -----------------------------------------------------------------------------------


def test_a_scripted_kill_of_the_carrier_drops_the_bomb_and_ends_its_decisions() -> None:
    agents = make_agents(["T", "T", "CT"], [0, 3, 5])  # the other T is 3 m away: no pickup
    # the carrier walks east (x = 0.05 m per tick); the others are asked at 1 and at 31
    policy = Script({0: [walk(E)], 1: [stop(30)], 2: [stop(30)]})
    sim = make_sim(agents, policy=policy, bomb_carrier=0)
    sim.run(to_tick=10)
    assert sim.bomb.status == BombStatus.CARRIED
    sim.kill(0, "scripted")
    death, drop = sim.events
    assert death == SimEvent(10, "death", 0, data={"reason": "scripted"})
    assert (drop.tick, drop.kind, drop.agent) == (10, "bomb_drop", 0)
    np.testing.assert_allclose(drop.data["position"], [0.5, 0.0, 0.0], atol=1e-9)
    assert (sim.bomb.status, sim.bomb.carrier) == (BombStatus.DROPPED, -1)
    assert (bool(sim.agents.alive[0]), int(sim.agents.hp[0])) == (False, 0)
    sim.kill(0, "again")  # a dead agent dies once
    assert len(sim.events) == 2
    sim.run(to_tick=40)
    assert sim.outcome is None  # a T is still alive
    assert [policy.ticks_of(a) for a in range(3)] == [[1], [1, 31], [1, 31]]
    assert sim.needs_decision.tolist() == [False, False, False]
    # the body stays where it fell, short of the node it was walking to
    np.testing.assert_allclose(sim.agents.position[0], [0.5, 0.0, 0.0], atol=1e-9)
    assert sim.agents.node[0] == 0


def test_killing_the_last_ct_ends_the_round_at_the_next_tick() -> None:
    sim = make_sim(t_and_ct())
    sim.run(to_tick=10)
    sim.kill(1, "scripted")
    assert not sim.done  # the outcome is checked by the tick
    sim.run()
    assert sim.outcome == RoundOutcome("T", "TerroristsWin", 11)
    assert [(e.tick, e.kind) for e in sim.events] == [(10, "death"), (11, "round_end")]


# ---- recording -------------------------------------------------------------------------------


def test_recording_at_requested_ticks_and_the_final_state_after_the_end() -> None:
    agents = make_agents(["T", "CT"], [0, 5], hp=np.array([100, 70]), yaw=np.array([90.0, 90.0]))
    policy = Script({0: [walk(E)] * 3})  # 0.05 m per tick, the whole round
    sim = make_sim(agents, policy=policy, record_ticks=[500, 10, 0, 30, 10, 31, 45])
    sim.run(to_tick=30)
    sim.kill(1, "scripted")  # the round ends at tick 31, with the T at x = 1.55 m
    rec = sim.run()
    assert sim.outcome == RoundOutcome("T", "TerroristsWin", 31)
    assert rec.ticks.tolist() == [0, 10, 30, 31, 45, 500]
    t_x = [0.0, 0.5, 1.5, 1.55, 1.55, 1.55]  # ticks 45 and 500: the final state of tick 31
    np.testing.assert_allclose(rec.position[:, 0, 0], t_x, atol=1e-9)
    np.testing.assert_allclose(rec.position[:, 1], [[5.0, 0.0, 0.0]] * 6)
    np.testing.assert_allclose(rec.position[:, 0, 1:], 0.0)
    assert rec.yaw.tolist() == [[90.0, 90.0]] + [[0.0, 90.0]] * 5  # the walker faces east
    # tick 30 was recorded by its step, before the kill that followed it
    assert rec.hp.tolist() == [[100, 70]] * 3 + [[100, 0]] * 3
    assert rec.alive.tolist() == [[True, True]] * 3 + [[True, False]] * 3
    assert rec.events is sim.events


def test_ticks_before_the_start_tick_are_not_recorded() -> None:
    rec = make_sim(t_and_ct(), start_tick=10, record_ticks=[5, 10, 11]).run()
    assert rec.ticks.tolist() == [5, 10, 11]
    assert np.isnan(rec.position[0]).all()
    assert rec.alive[0].tolist() == [False, False]
    assert rec.position[1:, :, 0].tolist() == [[0.0, 5.0], [0.0, 5.0]]
    assert rec.alive[1:].tolist() == [[True, True], [True, True]]


def test_nothing_requested_nothing_recorded() -> None:
    rec = make_sim(t_and_ct()).run()
    assert rec.ticks.tolist() == []
    assert rec.position.shape == (0, 2, 3)


def test_a_relocation_from_outside_a_decision_asks_the_agent_again() -> None:
    """A walking agent relocated by the caller between ticks (not by its own policy) stops its
    walk and is asked for a decision at the next tick, from the new node."""
    policy = Script({0: [walk(E), walk(W)]})
    sim = make_sim(t_and_ct(), policy=policy)
    sim.run(to_tick=5)  # walking node 0 -> 1
    sim.relocate(0, 3)
    assert sim.needs_decision.tolist() == [True, False]
    sim.step()
    assert policy.ticks_of(0) == [1, 6]
    sim.run(to_tick=6 + WALK_3)
    assert sim.agents.node[0] == 2  # walked west from node 3


def test_agent_arrays_of_another_length_are_refused() -> None:
    with pytest.raises(ValueError, match="2 hp for 3 agents"):
        make_agents(["T", "T", "CT"], [0, 1, 5], hp=np.array([100, 100]))
    with pytest.raises(ValueError, match="2 nodes for 3 agents"):
        Agents.create(["a", "b", "c"], ["T", "T", "CT"], LINE.positions[[0, 1, 2]], [0, 1])
