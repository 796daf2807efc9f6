"""The event-by-event run (`Simulator.run`, which glides over ticks where only motion happens)
gives tick for tick what stepping every tick gives: the same recording, events and outcome, on
many seeded rounds with both movers, shooting and the bomb on."""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
import pytest
from busy_rounds import (
    Shots,
    Wanderers,
    assert_same_round,
    count_quiet_steps,
    every_tick,
    no_compiled_steps,
    play_busy,
    site_agents,
)

from decoy_cli.env.step import StepEnd
from decoy_cli.sim.engine import Simulator
from decoy_cli.sim.setup import RoundSetup, open_round
from decoy_cli.waypoints.build import builtin_graph
from decoy_cli.world.navmesh import nav_world
from decoy_cli.world.physics import PhysicsWorld

GRAPH = builtin_graph()


def _play(
    physics: PhysicsWorld, mover: str, seed: int, drive: Callable[[Simulator], None]
) -> Simulator:
    # recorded ticks that fall between combat steps too
    return play_busy(physics, GRAPH, mover, seed, Wanderers(seed), drive, range(0, 8000, 7))


def _event_by_event(sim: Simulator) -> None:
    sim.run()


@pytest.fixture(scope="module")
def physics():
    with PhysicsWorld(nav_world()) as world:
        yield world


@pytest.mark.parametrize("mover", ["kinematic", "physics"])
def test_run_is_tick_for_tick_what_stepping_every_tick_gives(physics, mover) -> None:
    kinds: set[str] = set()
    for seed in range(12):
        stepped = _play(physics, mover, seed, every_tick)
        glided = _play(physics, mover, seed, _event_by_event)
        assert_same_round(glided, stepped, seed)
        kinds |= {event.kind for event in stepped.events}
    # the rounds exercised what a glide must stop for
    assert {"damage", "kill", "plant", "bomb_drop", "defuse_start", "round_end"} <= kinds, kinds


def test_until_is_asked_whenever_more_than_motion_may_have_happened(physics) -> None:
    """Predicates on decisions and on deaths stop the run at the tick stepping stops at."""

    def decisions(count: int) -> Callable[[Simulator], bool]:
        return lambda sim: int(sim.state.decisions.sum()) >= count

    def deaths(count: int) -> Callable[[Simulator], bool]:
        return lambda sim: int((~sim.agents.alive).sum()) >= count

    # a count of decisions part way through each round (the whole round's count, stepped)
    totals = [
        int(_play(physics, "kinematic", seed, every_tick).state.decisions.sum())
        for seed in range(8)
    ]
    cases = [(seed, decisions(max(5, totals[seed] * (seed + 1) // 9))) for seed in range(8)]
    for seed, until in [*cases, (5, deaths(2)), (6, deaths(1))]:

        def step_until(sim: Simulator, until=until) -> None:
            while not sim.done and not until(sim):
                sim.step()

        stepped = _play(physics, "kinematic", seed, step_until)
        glided = _play(physics, "kinematic", seed, lambda sim, until=until: sim.run(until=until))
        assert until(stepped) and glided.tick == stepped.tick, seed
        assert glided.events == stepped.events


def test_the_environment_plays_the_same_episodes_as_stepping_every_tick(monkeypatch) -> None:
    """Its steps play quiet stretches in compiled code (`env_step`), stopping where an agent
    is due, as stepping every tick does."""
    from decoy_cli.env import DecoyParallelEnv

    def play() -> list:
        env = DecoyParallelEnv(mover="kinematic", damage_model=Shots())
        rng = np.random.default_rng(0)
        trace = []
        for seed in range(3):
            obs, infos = env.reset(seed=seed)
            while env.agents:
                actions = {
                    name: int(rng.choice(np.flatnonzero(obs[name]["action_mask"])))
                    for name in env.agents
                    if infos[name]["needs_decision"]
                }
                obs, rewards, ends, _, infos = env.step(actions)
                trace.append(ends)
                trace.append(({k: v["observation"].tolist() for k, v in obs.items()}, rewards))
        env.close()
        return trace

    ended = count_quiet_steps(monkeypatch)
    glided = play()
    assert ended.count(StepEnd.PLAYED) > 1000  # most steps ended in compiled code
    assert ended.count(StepEnd.LEFT_TO_RUN) > 50  # and others went on in Python

    no_compiled_steps(monkeypatch)
    assert play() == glided


def test_moving_on_after_the_end_event_by_event_is_stepping_after_the_end(physics) -> None:
    """A replay follows the data past the outcome (`after_end`): the same, tick for tick."""

    def stepped(sim: Simulator) -> None:
        every_tick(sim)
        for _ in range(400):
            sim.step(after_end=True)

    def glided(sim: Simulator) -> None:
        sim.run()
        sim.run(to_tick=sim.tick + 400, after_end=True)

    for seed in range(4):
        a = _play(physics, "kinematic", seed, stepped)
        b = _play(physics, "kinematic", seed, glided)
        assert a.outcome is not None and a.outcome == b.outcome and a.tick == b.tick
        assert a.events == b.events
        for name in ("position", "yaw", "hp", "alive"):
            np.testing.assert_array_equal(getattr(a.recording, name), getattr(b.recording, name))


def test_a_predicate_true_after_the_decisions_but_not_after_the_tick_does_not_stop() -> None:
    """The environment's predicate (someone needs a decision): the only agent due next is
    killed by the combat step of the very tick, so stepping goes on, and so must run."""
    from decoy_cli.sim.engine import Decision
    from decoy_cli.sim.state import Agents, SimEvent
    from decoy_cli.waypoints.graph import STOP_ACTION

    class Stopper:
        def decide(self, sim: Simulator, agent: int) -> Decision:
            return Decision(STOP_ACTION, hold_ticks=30 if agent == 0 else 2000)

    class KillsAgentZeroAt30:
        def run(self, agents: Agents, tick: int, rng: np.random.Generator) -> list[SimEvent]:
            if tick == 30 and agents.alive[0]:
                agents.alive[0], agents.hp[0] = False, 0
                return [SimEvent(tick, "kill", 0)]
            return []

    def due(sim: Simulator) -> bool:
        return sim.tick > 1 and bool(sim.needs_decision.any())

    def stepping(sim: Simulator) -> None:
        while not sim.done and not due(sim):
            sim.step()

    ends = []
    for drive in (stepping, lambda sim: sim.run(until=due)):
        setup = RoundSetup(graph=GRAPH, bomb=False)
        agents = site_agents(GRAPH, 0)
        with open_round(setup, agents, Stopper(), seed=0) as sim:
            sim.combat = KillsAgentZeroAt30()
            drive(sim)
        ends.append((sim.tick, sim.events))
    assert ends[0] == ends[1] and ends[0][0] > 30
