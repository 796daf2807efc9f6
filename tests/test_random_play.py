"""`RandomPolicy` playing quiet stretches in compiled code (`Simulator.run` with the kinematic
mover) gives tick for tick what stepping every tick gives, and what deciding one agent at a
time gives: the same recording, events, outcome and decisions on many seeded busy rounds."""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
import pytest
from busy_rounds import assert_same_round, count_stretch_decisions, every_tick, play_busy

from decoy_cli.sim.engine import Decision, Policy, Simulator
from decoy_cli.sim.random_play import RandomPolicy
from decoy_cli.waypoints.build import builtin_graph
from decoy_cli.waypoints.graph import STOP_ACTION
from decoy_cli.world.navmesh import nav_world
from decoy_cli.world.physics import PhysicsWorld

GRAPH = builtin_graph()


class OneAtATime:
    """The same random policy without its compiled stretches: one `decide` per agent."""

    def __init__(self, policy: RandomPolicy) -> None:
        self.policy = policy

    def decide(self, sim: Simulator, agent: int) -> Decision:
        return self.policy.decide(sim, agent)


def _policy(seed: int) -> RandomPolicy:
    return RandomPolicy(np.random.default_rng(seed), hold_ticks=1 + 97 * (seed % 4), defuse=True)


def _play(
    physics: PhysicsWorld, seed: int, policy: Policy, drive: Callable[[Simulator], None]
) -> Simulator:
    record = range(0, 8000, 7 + seed % 50)
    return play_busy(physics, GRAPH, "kinematic", seed, policy, drive, record)


@pytest.fixture(scope="module")
def physics():
    with PhysicsWorld(nav_world()) as world:
        yield world


@pytest.fixture()
def stretches(monkeypatch) -> list[int]:
    """The decisions made inside compiled stretches, call by call."""
    return count_stretch_decisions(monkeypatch)


def test_compiled_stretches_give_what_stepping_every_tick_gives(physics, stretches) -> None:
    kinds: set[str] = set()
    for seed in range(40):
        stepped = _play(physics, seed, OneAtATime(_policy(seed)), every_tick)
        compiled = _play(physics, seed, _policy(seed), lambda sim: sim.run())
        assert_same_round(compiled, stepped, seed)
        kinds |= {event.kind for event in stepped.events}
    assert {"damage", "kill", "plant", "bomb_drop", "defuse_start", "round_end"} <= kinds, kinds
    assert sum(stretches) > 1000  # most decisions were made in compiled stretches


def test_max_decisions_stops_where_a_decision_predicate_stops(physics, stretches) -> None:
    for seed, count in ((0, 1), (1, 37), (2, 400), (3, 2500)):
        asked = _play(
            physics, seed, OneAtATime(_policy(seed)),
            lambda sim, n=count: sim.run(lambda s: s.decision_count >= n),
        )  # fmt: skip
        capped = _play(physics, seed, _policy(seed), lambda sim, n=count: sim.run(max_decisions=n))
        assert_same_round(capped, asked, seed)
        assert capped.decision_count == asked.decision_count >= min(count, 1)
    assert sum(stretches) > 0


def test_random_policy_picks_only_possible_actions_uniformly() -> None:
    policy = RandomPolicy(np.random.default_rng(0))
    node = int(np.argmax((GRAPH.out_edges >= 0).sum(axis=1) == 3))
    allowed = set(np.flatnonzero(GRAPH.action_mask(node)).tolist())

    class Sim:  # what `decide` reads of a simulator
        graph = GRAPH
        agents = type("A", (), {"node": np.array([node]), "count": 1})()

    picks = [policy.decide(Sim(), 0).action for _ in range(4000)]  # type: ignore[arg-type]
    counts = np.bincount(picks, minlength=9)
    assert set(np.flatnonzero(counts).tolist()) == allowed
    assert len(allowed) == 4 and counts[list(allowed)].min() > 4000 / 4 * 0.9
    stop = policy._choices.decision(0, STOP_ACTION)
    assert stop.plant and not stop.defuse and stop.hold_ticks == 30
