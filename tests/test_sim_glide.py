"""The event-by-event run (`Simulator.run`, which glides over ticks where only motion happens)
gives tick for tick what stepping every tick gives: the same recording, events and outcome, on
many seeded rounds with both movers, shooting and the bomb on."""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
import pytest

from decoy_cli.sim.combat import CombatBatch, DamageResult
from decoy_cli.sim.engine import Decision, Simulator
from decoy_cli.sim.setup import RoundSetup, open_round
from decoy_cli.sim.state import Agents
from decoy_cli.waypoints.build import builtin_graph
from decoy_cli.waypoints.graph import STOP_ACTION, WaypointGraph
from decoy_cli.world.navmesh import nav_world
from decoy_cli.world.physics import PhysicsWorld

GRAPH = builtin_graph()


class Shots:
    """A damage model that hits a tenth of the visible pairs for 10 HP (drawn from the
    engine's generator, so both runs must ask it at the same ticks in the same order)."""

    def __call__(self, batch: CombatBatch, rng: np.random.Generator) -> DamageResult:
        hit = rng.random(len(batch)) < 0.1
        groups = np.where(hit, 2, -1).astype(np.int8)
        return DamageResult(np.where(hit, 10, 0).astype(np.int64), groups, hit)


class Wanderers:
    """Random valid moves; a STOP (a quarter of the decisions) holds a random time and plants
    (a T) or defuses (a CT), so plants, aborts, pick-ups and defuses all happen."""

    def __init__(self, seed: int) -> None:
        self.rng = np.random.default_rng(seed)

    def decide(self, sim: Simulator, agent: int) -> Decision:
        mask = sim.graph.action_mask(int(sim.agents.node[agent]))
        if self.rng.random() < 0.25:
            t_side = sim.agents.side[agent] == "T"
            hold = int(self.rng.integers(1, 400))
            return Decision(STOP_ACTION, hold_ticks=hold, plant=t_side, defuse=not t_side)
        moves = np.flatnonzero(mask[:STOP_ACTION])
        return Decision(int(self.rng.choice(moves)), speed=float(self.rng.uniform(1.0, 6.0)))


def _agents(graph: WaypointGraph, seed: int) -> Agents:
    """Five T and five CT on one bomb site, close enough to see and shoot each other."""
    rng = np.random.default_rng(seed)
    site = graph.region_of("bombsite_a" if seed % 2 else "bombsite_b")
    nodes = rng.choice(site, 10, replace=False)
    return Agents.create(
        names=[f"p{i}" for i in range(10)],
        sides=["T"] * 5 + ["CT"] * 5,
        positions=graph.positions[nodes],
        nodes=nodes,
        weapons=["AK-47"] * 5 + ["M4A4"] * 5,
        has_defuser=np.array([False] * 5 + [True] * 5),
    )


def _play(
    physics: PhysicsWorld, mover: str, seed: int, drive: Callable[[Simulator], None]
) -> Simulator:
    setup = RoundSetup(graph=GRAPH, mover=mover, damage_model=Shots())
    record = range(0, 8000, 7)  # recorded ticks that fall between combat steps too
    with open_round(
        setup,
        _agents(GRAPH, seed),
        Wanderers(seed),
        physics=physics,
        bomb_carrier=seed % 5,
        record_ticks=record,
        seed=seed,
    ) as sim:
        drive(sim)
    return sim


def _every_tick(sim: Simulator) -> None:
    while not sim.done:
        sim.step()


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
        stepped = _play(physics, mover, seed, _every_tick)
        glided = _play(physics, mover, seed, _event_by_event)
        assert glided.outcome == stepped.outcome, seed
        assert glided.tick == stepped.tick, seed
        assert glided.events == stepped.events, seed
        for name in ("ticks", "position", "yaw", "hp", "alive"):
            a, b = getattr(glided.recording, name), getattr(stepped.recording, name)
            np.testing.assert_array_equal(a, b, err_msg=f"seed {seed}: {name}")
        np.testing.assert_array_equal(glided.decisions, stepped.decisions)
        kinds |= {event.kind for event in stepped.events}
    # the rounds exercised what a glide must stop for
    assert {"damage", "kill", "plant", "bomb_drop", "defuse_start", "round_end"} <= kinds, kinds


def test_until_is_asked_whenever_more_than_motion_may_have_happened(physics) -> None:
    """A predicate on decisions stops the run exactly where stepping every tick stops."""

    def enough(sim: Simulator) -> bool:
        return int(sim.decisions.sum()) >= 150

    def step_until(sim: Simulator) -> None:
        while not sim.done and not enough(sim):
            sim.step()

    stepped = _play(physics, "kinematic", 3, step_until)
    glided = _play(physics, "kinematic", 3, lambda sim: sim.run(until=enough))
    assert glided.tick == stepped.tick and int(glided.decisions.sum()) >= 150
    assert glided.events == stepped.events


def test_the_environment_plays_the_same_episodes_as_stepping_every_tick(monkeypatch) -> None:
    from decoy_cli.sim import DecoyParallelEnv

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

    glided = play()

    def every_tick(sim: Simulator, until=None):
        while not sim.done and not (until is not None and until(sim)):
            sim.step()
        return sim.recording

    monkeypatch.setattr(Simulator, "run", every_tick)
    assert play() == glided
