"""The array environment: the PettingZoo environment over it shows the same rounds step for step
(what the wrapper adds: dictionaries, names, the agents list), its rewards and terminations at
deaths and the round's end, and its checks of bad actions. The game's own rules, spawns,
seeding, masks and timing are tested through the PettingZoo API in tests/test_sim_env.py."""

from __future__ import annotations

import dataclasses
import os
import subprocess
import sys
from collections.abc import Callable, Iterator

import numpy as np
import pytest
from busy_rounds import Shots, count_quiet_steps, no_compiled_steps

from decoy_cli.env.array_env import ArrayStep, DecoyArrayEnv
from decoy_cli.env.parallel import DecoyParallelEnv
from decoy_cli.env.step import StepEnd
from decoy_cli.sim.combat import HIT_GROUPS, CombatBatch, DamageResult
from decoy_cli.sim.state import BombStatus
from decoy_cli.waypoints.graph import STOP_ACTION


class AlwaysHits:
    """Every visible pair is hit in the chest for 40: deaths within a few combat steps."""

    def __call__(self, batch: CombatBatch, rng: np.random.Generator) -> DamageResult:
        k = len(batch)
        groups = np.full(k, HIT_GROUPS.index("Chest"), np.int8)
        return DamageResult(np.full(k, 40, np.int64), groups, np.ones(k, bool))


@pytest.fixture
def env() -> Iterator[DecoyArrayEnv]:
    environment = DecoyArrayEnv(damage_model=AlwaysHits())
    yield environment
    environment.close()


def close_in(env: DecoyArrayEnv | DecoyParallelEnv) -> None:
    """Put ct_0 and ct_1 on t_0's waypoint: t_0 dies within a few combat steps, mid-round."""
    sim = env.sim
    assert sim is not None
    for ct in (5, 6):
        sim.relocate(ct, int(sim.agents.node[0]))


def random_masked(state: ArrayStep, rng: np.random.Generator) -> np.ndarray:
    """A uniformly random allowed action for every agent (only the due ones are used)."""
    return np.argmax(rng.random(state.action_masks.shape) * state.action_masks, axis=1)


def test_the_pettingzoo_environment_plays_the_same_rounds_step_for_step() -> None:
    arrays = DecoyArrayEnv(damage_model=AlwaysHits())
    dicts = DecoyParallelEnv(damage_model=AlwaysHits())
    names = dicts.possible_agents
    deaths = ends = 0
    for seed in range(2):  # two rounds played to their end, with deaths on the way (below)
        rng = np.random.default_rng(seed)
        state = arrays.reset(seed)
        obs, infos = dicts.reset(seed=seed)
        close_in(arrays)
        close_in(dicts)
        while True:
            for k, name in enumerate(names):
                if name in obs:
                    np.testing.assert_array_equal(obs[name]["observation"], state.observations[k])
                    np.testing.assert_array_equal(obs[name]["action_mask"], state.action_masks[k])
                    assert infos[name]["needs_decision"] == state.needs_decision[k]
                    assert infos[name]["tick"] == state.tick
            if state.winner is not None:
                break
            actions = random_masked(state, rng)
            state = arrays.step(actions)
            live = list(dicts.agents)
            obs, rewards, terminations, _, infos = dicts.step(
                {name: int(actions[names.index(name)]) for name in live}
            )
            for name in live:
                k = names.index(name)
                assert rewards[name] == state.rewards[k]
                assert terminations[name] == state.terminated[k]
            assert dicts.agents == [name for k, name in enumerate(names) if state.active[k]]
            deaths += int((state.terminated & (state.winner is None)).sum())
        ends += 1
        assert {info["winner"] for info in infos.values()} == {state.winner}
    arrays.close()
    dicts.close()
    assert ends == 2 and deaths > 0  # rounds that end, with deaths along the way


def test_rewards_and_terminations_follow_deaths_and_the_round_end(env: DecoyArrayEnv) -> None:
    rng = np.random.default_rng(7)
    state = env.reset(3)
    close_in(env)
    assert state.active.all() and not state.terminated.any() and not state.rewards.any()
    left_early = np.zeros(10, bool)
    while state.winner is None:
        before = state.active
        state = env.step(random_masked(state, rng))
        assert not (state.terminated & ~before).any()  # only agents still in the episode leave
        assert (state.active == (before & ~state.terminated)).all()
        if state.winner is None:
            assert not state.rewards.any()
            assert not state.needs_decision[~state.active].any()  # the dead decide nothing
            left_early |= state.terminated
    assert left_early.any()
    assert not state.active.any() and not state.needs_decision.any()
    won = np.array(env.sides) == state.winner
    finished = ~left_early
    np.testing.assert_array_equal(state.rewards[finished], np.where(won, 1.0, -1.0)[finished])
    assert not state.rewards[left_early].any()  # an agent that died earlier left with 0
    assert state.rewards.dtype == np.float32
    with pytest.raises(RuntimeError, match="reset"):
        env.step(np.full(10, STOP_ACTION))


def test_actions_of_agents_not_due_are_ignored_and_bad_actions_named(env: DecoyArrayEnv) -> None:
    with pytest.raises(RuntimeError, match="reset"):
        env.step(np.zeros(10, np.int64))
    state = env.reset(0)
    assert state.needs_decision.all()
    actions = np.full(10, STOP_ACTION)
    for bad in (np.zeros(9, np.int64), np.zeros(10, np.float64), np.zeros((10, 1), np.int64)):
        with pytest.raises(ValueError, match=r"\(10,\) integers"):
            env.step(bad)
    actions[6] = 9
    with pytest.raises(ValueError, match=r"ct_1: action 9 is not in 0\.\.8"):
        env.step(actions)
    actions[6] = STOP_ACTION
    state = env.step(actions)  # everyone holds a STOP: nobody is due until it ends
    assert state.tick == env.stop_ticks and state.needs_decision.all()
    actions = np.full(10, STOP_ACTION, np.int32)  # any integer type
    actions[0] = int(np.flatnonzero(state.action_masks[0, :STOP_ACTION])[0])  # t_0 walks
    state = env.step(actions)
    assert state.needs_decision[0] and not state.needs_decision[1:].any()  # t_0 arrived first
    actions = np.full(10, -5)  # the agents not due may be given anything
    actions[0] = STOP_ACTION
    env.step(actions)


def _same_state(one: ArrayStep, other: ArrayStep) -> bool:
    return all(
        np.array_equal(a, b) if isinstance(a, np.ndarray) else a == b
        for a, b in zip(dataclasses.astuple(one), dataclasses.astuple(other), strict=True)
    )


@pytest.mark.parametrize("map_name", ["dust2", "nuke"])
def test_compiled_steps_give_what_stepping_every_tick_gives(monkeypatch, map_name) -> None:
    """Quiet steps are played in one compiled call (`env_step`); with none of it and every
    tick stepped, the same actions give the same states step for step, and the same events:
    deaths, dropped bombs, impossible moves, the drops and ladders of de_nuke."""

    def play() -> tuple[list[ArrayStep], list]:
        env = DecoyArrayEnv(map=map_name, damage_model=Shots(share=0.5, damage=25))
        graph = env.graph
        edges = graph.out_edges
        damaging = (edges >= 0) & (graph.fall_m[np.maximum(edges, 0)] > 0)
        rng = np.random.default_rng(1)
        states, events = [], []
        for seed in range(3):
            state = env.reset(seed)
            assert env.sim is not None
            if seed == 0:  # onto damaging drops, which they take: fall damage
                others = [t for t in range(5) if t != env.sim.bomb.carrier]
                for agent, node in zip(
                    others, np.flatnonzero(damaging.any(axis=1))[:3], strict=False
                ):
                    env.sim.relocate(agent, int(node))
            if seed == 1:  # onto the bomb carrier: fights, deaths, a dropped bomb
                for ct in (5, 6, 7, 8):
                    env.sim.relocate(ct, int(env.sim.agents.node[env.sim.bomb.carrier]))
            steps = 0
            while state.winner is None:
                actions = random_masked(state, rng)
                wild = rng.random(len(actions)) < 0.03  # any action, possible or not
                actions[wild] = rng.integers(0, STOP_ACTION + 1, int(wild.sum()))
                drops = damaging[env.sim.agents.node]  # take damaging drops where there are
                taken = drops.any(axis=1) & state.needs_decision
                actions[taken] = np.argmax(drops[taken], axis=1)
                state = env.step(actions)
                states.append(state)
                steps += 1
                if seed == 2 and steps > 300 and not state.needs_decision[5:].any():
                    for ct in np.flatnonzero(env.sim.agents.alive[5:]) + 5:
                        env.sim.kill(int(ct), "test")  # from outside: the round ends
            events += [*env.sim.events, _round_summary(env)]
        env.close()
        return states, events

    kinds = _compiled_against_stepping(monkeypatch, play, played=500, left=50)
    assert {"kill", "death", "bomb_drop", "invalid_action", "round_end"} <= kinds, kinds
    assert "fall_damage" in kinds


def test_compiled_steps_with_plants_and_defuses_give_what_stepping_gives(monkeypatch) -> None:
    """Everyone on bomb site A, the Ts stopping often (a STOP holds 6 s) and CTs put beside a
    planted bomb: plants, defuses, explosions, the same with no tick quiet."""

    def play() -> tuple[list[ArrayStep], list]:
        env = DecoyArrayEnv(damage_model=Shots(share=0.05), stop_seconds=6.0)
        site = env.graph.region_of("bombsite_a")
        rng = np.random.default_rng(7)
        states, events = [], []
        for seed in range(8):
            state = env.reset(seed)
            assert env.sim is not None
            for agent, node in enumerate(rng.choice(site, 10, replace=False)):
                env.sim.relocate(agent, int(node))
            moved = 0
            while state.winner is None:
                bomb = env.sim.bomb
                if bomb.status == BombStatus.PLANTED and moved < 3:
                    offsets = env.graph.positions - bomb.position
                    near = int(np.argmin(np.linalg.norm(offsets, axis=1)))
                    for ct in np.flatnonzero(state.needs_decision[5:])[: 3 - moved] + 5:
                        env.sim.relocate(int(ct), near)  # a CT due: asked again anyway
                        moved += 1
                actions = random_masked(state, rng)
                stop = rng.random(10) < np.where(np.arange(10) >= 5, 0.8, 0.4)
                actions[stop] = STOP_ACTION
                state = env.step(actions)
                states.append(state)
            events += [*env.sim.events, _round_summary(env)]
        env.close()
        return states, events

    kinds = _compiled_against_stepping(monkeypatch, play, played=100, left=20)
    assert {"plant", "defuse_start", "defuse"} <= kinds, kinds


def _compiled_against_stepping(
    monkeypatch: pytest.MonkeyPatch,
    play: Callable[[], tuple[list[ArrayStep], list]],
    played: int,
    left: int,
) -> set[str | None]:
    """`play()` with compiled steps (more than `played` played to their end, more than `left`
    going on in Python), then with no tick quiet: the same states step for step and the same
    events and round summaries. Returns the kinds of events seen."""
    ended = count_quiet_steps(monkeypatch)
    compiled, compiled_events = play()
    assert ended.count(StepEnd.PLAYED) > played and ended.count(StepEnd.LEFT_TO_RUN) > left
    no_compiled_steps(monkeypatch)
    stepped, stepped_events = play()
    assert len(compiled) == len(stepped)
    for k, (one, other) in enumerate(zip(compiled, stepped, strict=True)):
        assert _same_state(one, other), k
    assert compiled_events == stepped_events
    return {getattr(event, "kind", None) for event in stepped_events}


def _round_summary(env: DecoyArrayEnv) -> tuple:
    """What a round left in its simulator beside the events: outcome, tick, decisions, the
    agents' positions, yaw, health and life, and the bomb."""
    sim = env.sim
    assert sim is not None
    agents, bomb = sim.agents, sim.bomb
    return (
        sim.outcome, sim.tick, sim.decision_count, sim.state.decisions.tolist(),
        agents.position.tobytes(), agents.yaw.tobytes(), agents.hp.tolist(),
        agents.alive.tolist(), bomb.status, bomb.carrier, bomb.site, bomb.position.tobytes(),
    )  # fmt: skip


def test_an_agent_made_due_from_outside_is_named(env: DecoyArrayEnv) -> None:
    """Relocating an agent between steps makes it due at the next tick, unasked: the step
    says which agent the simulator asked."""
    rng = np.random.default_rng(2)
    state = env.reset(2)
    for _ in range(40):
        state = env.step(random_masked(state, rng))
    assert env.sim is not None
    while env.sim.quiet_horizon() == env.sim.tick:  # the next tick is quiet: a compiled step
        state = env.step(random_masked(state, rng))
    idle = int(np.flatnonzero(~state.needs_decision & state.active)[0])
    env.sim.relocate(idle, int(env.sim.agents.node[idle]))
    with pytest.raises(RuntimeError, match=f"asked agent {idle} for a decision"):
        env.step(random_masked(state, rng))


def test_the_environment_plays_with_numba_off() -> None:
    """With NUMBA_DISABLE_JIT the compiled steps run as Python (a plain object holds the
    round's arrays), for debugging: a few steps in a fresh process."""
    script = (
        "import numpy as np\n"
        "from decoy_cli.env.array_env import DecoyArrayEnv\n"
        "env = DecoyArrayEnv(combat=False)\n"
        "state = env.reset(0)\n"
        "rng = np.random.default_rng(0)\n"
        "for _ in range(5):\n"
        "    masks = state.action_masks\n"
        "    state = env.step(np.argmax(rng.random(masks.shape) * masks, 1))\n"
        "print('tick', state.tick)\n"
    )
    done = subprocess.run(
        [sys.executable, "-c", script],
        env={**os.environ, "NUMBA_DISABLE_JIT": "1"},
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert done.returncode == 0, done.stderr[-2000:]
    assert int(done.stdout.split()[-1]) > 0
