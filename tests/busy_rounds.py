"""Busy simulated rounds for engine tests: five T and five CT on one bomb site, random walkers
that plant, defuse and shoot (not real data), so that every mechanic fires within a round."""

from __future__ import annotations

from collections.abc import Callable, Iterable

import numpy as np
import pytest

from decoy_cli.sim.combat import CombatBatch, DamageResult
from decoy_cli.sim.engine import Decision, Policy, Simulator
from decoy_cli.sim.movement import KinematicMover
from decoy_cli.sim.random_play import RandomPolicy
from decoy_cli.sim.rules import BombRules, RulesConfig
from decoy_cli.sim.setup import RoundSetup, open_round
from decoy_cli.sim.sites import SiteZones
from decoy_cli.sim.state import Agents
from decoy_cli.waypoints.graph import STOP_ACTION, WaypointGraph
from decoy_cli.world.physics import PhysicsWorld


class Shots:
    """A damage model that hits a `share` of the visible pairs (a tenth) for `damage` HP (10),
    drawn from the engine's generator, so both runs must ask it at the same ticks in the same
    order."""

    def __init__(self, share: float = 0.1, damage: int = 10) -> None:
        self.share = share
        self.damage = damage

    def __call__(self, batch: CombatBatch, rng: np.random.Generator) -> DamageResult:
        hit = rng.random(len(batch)) < self.share
        groups = np.where(hit, 2, -1).astype(np.int8)
        return DamageResult(np.where(hit, self.damage, 0).astype(np.int64), groups, hit)


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


def site_agents(graph: WaypointGraph, seed: int) -> Agents:
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


def play_busy(
    physics: PhysicsWorld,
    graph: WaypointGraph,
    mover: str,
    seed: int,
    policy: Policy,
    drive: Callable[[Simulator], object],
    record_ticks: Iterable[int],
) -> Simulator:
    """A busy round (`site_agents`, `Shots`, carrier by the seed) driven by `drive`."""
    setup = RoundSetup(graph=graph, mover=mover, damage_model=Shots())
    with open_round(
        setup,
        site_agents(graph, seed),
        policy,
        physics=physics,
        bomb_carrier=seed % 5,
        record_ticks=list(record_ticks),
        seed=seed,
    ) as sim:
        drive(sim)
    return sim


def every_tick(sim: Simulator) -> None:
    while not sim.done:
        sim.step()


def assert_same_round(a: Simulator, b: Simulator, seed: int) -> None:
    """The same outcome, end tick, events, recording, decisions and bomb."""
    assert a.outcome == b.outcome, seed
    assert a.tick == b.tick, seed
    assert a.events == b.events, seed
    assert a.decision_count == b.decision_count == int(a.state.decisions.sum()), seed
    assert (a.bomb.status, a.bomb.carrier, a.bomb.site) == (
        b.bomb.status,
        b.bomb.carrier,
        b.bomb.site,
    )
    np.testing.assert_array_equal(a.bomb.position, b.bomb.position, err_msg=f"seed {seed}: bomb")
    for name in ("ticks", "position", "yaw", "hp", "alive"):
        x, y = getattr(a.recording, name), getattr(b.recording, name)
        np.testing.assert_array_equal(x, y, err_msg=f"seed {seed}: {name}")
    np.testing.assert_array_equal(a.state.decisions, b.state.decisions)


def _recorded(monkeypatch: pytest.MonkeyPatch, module: object, name: str, entry: int) -> list[int]:
    """From now on, entry `entry` of what each call of `module.name` returns, call by call."""
    seen: list[int] = []
    function = getattr(module, name)

    def recording(*args):
        out = function(*args)
        seen.append(int(out[entry]))
        return out

    monkeypatch.setattr(module, name, recording)
    return seen


def count_stretch_decisions(monkeypatch: pytest.MonkeyPatch) -> list[int]:
    """From now on, the decisions each compiled stretch makes (`quiet_play.play_quiet`), call by
    call: a test that the compiled path was taken."""
    from decoy_cli.sim import quiet_play

    return _recorded(monkeypatch, quiet_play, "play_quiet", 2)


def count_quiet_steps(monkeypatch: pytest.MonkeyPatch) -> list[int]:
    """From now on, how each of the environment's compiled steps ended (`env_step`'s
    `_quiet_step`: `StepEnd.PLAYED` when it played the step to its end), call by call."""
    from decoy_cli.env import step as env_step

    return _recorded(monkeypatch, env_step, "_quiet_step", 0)


def no_compiled_steps(monkeypatch: pytest.MonkeyPatch) -> None:
    """From now on, the environment's steps play every tick with `Simulator.step` (no tick is
    quiet): the reference its compiled steps are compared with."""
    monkeypatch.setattr(Simulator, "quiet_horizon", lambda sim: sim.tick)


def random_round(
    graph: WaypointGraph, nodes: np.ndarray, seed: int, compiled: bool, ticks: int, every: int
) -> Simulator:
    """Random play (`RandomPolicy`, a STOP holds 5 ticks) of 4 T and 4 CT from `nodes` with
    the kinematic mover, where nobody can plant, recorded every `every` ticks, for `ticks`:
    `compiled` runs it (`Simulator.run`: quiet stretches in compiled code), else it steps every
    tick with the same policy deciding one agent at a time."""
    sides = ["T"] * 4 + ["CT"] * 4
    agents = Agents.create([f"p{k}" for k in range(8)], sides, graph.positions[nodes], nodes)
    policy = RandomPolicy(np.random.default_rng(seed), hold_ticks=5)
    chosen = policy if compiled else type("OneAtATime", (), {"decide": policy.decide})()
    rules = BombRules(SiteZones(nodes={"A": [[100.0, 100.0, 0.0]]}), RulesConfig())
    sim = Simulator(graph, agents, KinematicMover(), chosen, rules, seed=0,
                    record_ticks=range(0, ticks, every))  # fmt: skip
    if compiled:
        sim.run(to_tick=ticks)
    else:
        while sim.tick < ticks and not sim.done:
            sim.step()
    return sim
