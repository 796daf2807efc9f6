"""The PettingZoo environment: both API tests, seeding, action masks against the graph, STOP
timing, the bomb through STOP, deaths, round ends, rendering, and the pybullet client's life."""

from __future__ import annotations

import warnings
from collections.abc import Iterator

import numpy as np
import pybullet
import pytest
from pettingzoo.test import api_test, parallel_api_test, parallel_seed_test
from pettingzoo.utils.conversions import parallel_to_aec

from decoy_cli.env.observation import BOMB_STATES, POSITION_MARGIN_M, observation_layout
from decoy_cli.env.parallel import DecoyParallelEnv
from decoy_cli.sim.combat import HIT_GROUPS, CombatBatch, DamageResult
from decoy_cli.sim.rules import RulesConfig, SiteZones
from decoy_cli.waypoints.build import builtin_graph
from decoy_cli.waypoints.graph import STOP_ACTION

END_REASONS = {
    "TargetBombed": "T",
    "BombDefused": "CT",
    "CTWin": "CT",
    "TerroristsWin": "T",
    "TargetSaved": "CT",
}
RULES = RulesConfig()
DICT_OBSERVATION_WARNINGS = {
    "Observation is not a NumPy array",
    "Observation space for each agent probably should be gymnasium.spaces.box or "
    "gymnasium.spaces.discrete",
}


@pytest.fixture
def env() -> Iterator[DecoyParallelEnv]:
    environment = DecoyParallelEnv()
    yield environment
    environment.close()


def random_actions(obs: dict, agents: list[str], rng: np.random.Generator) -> dict[str, int]:
    """A uniformly random allowed action for every agent in the episode."""
    return {name: int(rng.choice(np.flatnonzero(obs[name]["action_mask"]))) for name in agents}


def all_stop(env: DecoyParallelEnv) -> dict[str, int]:
    return dict.fromkeys(env.agents, STOP_ACTION)


def entry(env: DecoyParallelEnv, obs: dict, agent: str, name: str) -> np.ndarray:
    return obs[agent]["observation"][env.layout[name]]


# ---- PettingZoo's own checks ------------------------------------------------------------------


def test_parallel_api(env: DecoyParallelEnv) -> None:
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        parallel_api_test(env, num_cycles=300)


def test_aec_api() -> None:
    env = DecoyParallelEnv(n_t=3, n_ct=2, render_mode="rgb_array")
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        api_test(parallel_to_aec(env), num_cycles=100)
    env.close()
    # the two warnings every Dict observation with an action mask gets (PettingZoo exempts its
    # own such environments by name)
    assert {str(w.message) for w in caught} <= DICT_OBSERVATION_WARNINGS


# ---- spaces and observations ------------------------------------------------------------------


def test_spaces_are_cached_and_observation_layout_is_documented(env: DecoyParallelEnv) -> None:
    assert env.possible_agents == [f"t_{k}" for k in range(5)] + [f"ct_{k}" for k in range(5)]
    for agent in env.possible_agents:
        assert env.observation_space(agent) is env.observation_space(agent)
        assert env.action_space(agent) is env.action_space(agent)
        assert env.action_space(agent).n == 9
    layout = observation_layout(4, 5)
    assert layout == env.layout
    starts = [s.start for s in layout.values()]
    stops = [s.stop for s in layout.values()]
    assert starts[0] == 0 and starts[1:] == stops[:-1]  # contiguous, in order
    assert stops[-1] == 72 == env.observation_space("t_0")["observation"].shape[0]
    box = env.observation_space("t_0")["observation"]
    assert box.dtype == np.float32 and np.all(box.high == 1.0)
    assert box.low[layout["position"]].tolist() == [-1.0] * 3
    assert box.low[layout["hp"]].tolist() == [0.0]


def test_observation_matches_the_state(env: DecoyParallelEnv) -> None:
    obs, infos = env.reset(seed=4)
    sim = env.sim
    carrier = sim.bomb.carrier
    assert sim.agents.side[carrier] == "T"
    for k, name in enumerate(env.possible_agents):
        hp, has_bomb, is_ct = (entry(env, obs, name, n)[0] for n in ("hp", "has_bomb", "is_ct"))
        assert hp == 1.0 and has_bomb == (k == carrier) and is_ct == name.startswith("ct")
        assert entry(env, obs, name, "needs_decision")[0] == 1.0 and infos[name]["needs_decision"]
        assert entry(env, obs, name, "bomb_state").tolist() == [0, 1, 0, 0, 0, 0]
        assert entry(env, obs, name, "round_time_left")[0] == 1.0
        assert entry(env, obs, name, "yaw").tolist() == [0.0, 1.0]  # facing east
    # t_0's first teammate slot is t_1, its first enemy slot is ct_0: alive, offset, hp
    graph = env.graph
    size = graph.positions.max(axis=0) - graph.positions.min(axis=0) + 2 * POSITION_MARGIN_M
    teammate = entry(env, obs, "t_0", "teammates")[:5]
    enemy = entry(env, obs, "t_0", "enemies")[:5]
    offset_t1 = (sim.agents.position[1] - sim.agents.position[0]) / size
    offset_ct0 = (sim.agents.position[5] - sim.agents.position[0]) / size
    np.testing.assert_allclose(teammate, [1.0, *offset_t1, 1.0], atol=1e-6)
    np.testing.assert_allclose(enemy, [1.0, *offset_ct0, 1.0], atol=1e-6)
    assert env.observation_space("t_0").contains(obs["t_0"])


def test_spawns_are_distinct_waypoints_of_the_spawn_regions(env: DecoyParallelEnv) -> None:
    graph = builtin_graph()
    for seed in range(5):
        env.reset(seed=seed)
        nodes = env.sim.agents.node
        assert len(set(nodes.tolist())) == 10
        assert set(nodes[:5].tolist()) <= set(graph.region_of("t_spawn").tolist())
        assert set(nodes[5:].tolist()) <= set(graph.region_of("ct_spawn").tolist())
        np.testing.assert_array_equal(env.sim.agents.position, graph.positions[nodes])
        assert env.sim.agents.weapon.tolist() == ["Glock-18"] * 5 + ["USP-S"] * 5


# ---- seeding ----------------------------------------------------------------------------------


def run_random(env: DecoyParallelEnv, seed: int, steps: int) -> list[np.ndarray]:
    """Observations of all agents over `steps` random masked steps after reset(seed)."""
    rng = np.random.default_rng(100 + seed)
    obs, _ = env.reset(seed=seed)
    seen = [np.stack([obs[a]["observation"] for a in env.possible_agents])]
    for _ in range(steps):
        obs, *_ = env.step(random_actions(obs, env.agents, rng))
        seen.append(np.stack([obs[a]["observation"] for a in env.possible_agents]))
    return seen


def test_pettingzoo_seed_test() -> None:
    parallel_seed_test(lambda: DecoyParallelEnv(n_t=3, n_ct=3), num_cycles=100)


def test_same_seed_same_round(env: DecoyParallelEnv) -> None:
    other = DecoyParallelEnv()
    first = run_random(env, seed=7, steps=300)
    second = run_random(other, seed=7, steps=300)
    assert all(np.array_equal(a, b) for a, b in zip(first, second, strict=True))
    assert other.sim.tick == env.sim.tick and other.sim.tick > 300
    different = run_random(other, seed=8, steps=0)
    assert not np.array_equal(first[0], different[0])
    # a reset without a seed continues the generator: a new round, and the same one again
    # after re-seeding
    env.reset(seed=7)
    after_seed = env.sim.agents.node.copy()
    env.reset()
    assert not np.array_equal(env.sim.agents.node, after_seed)


# ---- action masks and decision timing ---------------------------------------------------------


def test_masks_are_the_graph_out_edges(env: DecoyParallelEnv) -> None:
    graph = env.graph
    rng = np.random.default_rng(3)
    obs, infos = env.reset(seed=3)
    checked = 0
    for _ in range(150):
        sim = env.sim
        for name in env.agents:
            k = env.possible_agents.index(name)
            mask = obs[name]["action_mask"]
            assert mask.dtype == np.int8
            flag = entry(env, obs, name, "needs_decision")[0]
            assert bool(flag) == infos[name]["needs_decision"]
            if infos[name]["needs_decision"]:
                node = sim.agents.node[k]
                np.testing.assert_array_equal(sim.agents.position[k], graph.positions[node])
                assert mask[:8].tolist() == (graph.out_edges[node] >= 0).tolist()
                assert mask[8] == 1
                checked += 1
            else:
                assert mask.tolist() == [0] * 8 + [1]
        assert any(info["needs_decision"] for info in infos.values())
        obs, _, _, _, infos = env.step(random_actions(obs, env.agents, rng))
    assert checked > 150


def test_stop_holds_thirty_ticks(env: DecoyParallelEnv) -> None:
    rng = np.random.default_rng(5)
    obs, _ = env.reset(seed=5)
    assert env.stop_ticks == 30
    actions = random_actions(obs, env.agents, rng)
    actions["t_0"] = STOP_ACTION
    start = env.sim.agents.position[0].copy()
    obs, _, _, _, infos = env.step(actions)  # decided at tick 1: next decision at tick 31
    returns = []
    while not infos["t_0"]["needs_decision"]:
        np.testing.assert_array_equal(env.sim.agents.position[0], start)
        returns.append(env.sim.tick)
        actions = random_actions(obs, env.agents, rng)
        obs, _, _, _, infos = env.step(actions)
    assert env.sim.tick == 30  # the state after tick 30; t_0 decides at tick 31
    np.testing.assert_array_equal(env.sim.agents.position[0], start)
    assert len(returns) > 1  # other agents decided in between


def test_all_stop_is_one_step_of_thirty_ticks(env: DecoyParallelEnv) -> None:
    env.reset(seed=5)
    start = env.sim.agents.position.copy()
    for end in (30, 60):
        _, _, _, _, infos = env.step(all_stop(env))
        assert env.sim.tick == end
        assert all(info["needs_decision"] for info in infos.values())
        np.testing.assert_array_equal(env.sim.agents.position, start)


def test_ignored_actions_and_invalid_moves(env: DecoyParallelEnv) -> None:
    rng = np.random.default_rng(9)
    obs, _ = env.reset(seed=9)
    graph = env.graph
    blocked = {}
    for name in env.agents:
        k = env.possible_agents.index(name)
        missing = np.flatnonzero(graph.out_edges[env.sim.agents.node[k]] < 0)
        blocked[name] = int(missing[0]) if len(missing) else STOP_ACTION
    start = env.sim.agents.position.copy()
    env.step(blocked)  # masked-out moves stand still like a STOP
    invalid = [e for e in env.sim.events if e.kind == "invalid_action"]
    assert len(invalid) == sum(a != STOP_ACTION for a in blocked.values()) > 0
    assert env.sim.tick == 30
    np.testing.assert_array_equal(env.sim.agents.position, start)
    # agents that do not need a decision have their action ignored, whatever it is
    obs, *_ = env.step(random_actions(obs, env.agents, rng))
    waiting = [n for n in env.agents if not entry(env, obs, n, "needs_decision")[0]]
    assert waiting
    decisions = env.sim.state.decisions.copy()
    actions = random_actions(obs, env.agents, rng)
    actions.update(dict.fromkeys(waiting, 0))
    env.step(actions)
    for name in waiting:
        assert (
            env.sim.state.decisions[env.possible_agents.index(name)]
            == decisions[env.possible_agents.index(name)]
        )


def test_bad_actions_are_refused(env: DecoyParallelEnv) -> None:
    with pytest.raises(RuntimeError, match="reset"):
        env.step({})
    env.reset(seed=0)
    with pytest.raises(ValueError, match="needs a decision"):
        env.step({"t_0": 0})
    with pytest.raises(ValueError, match="not in the episode"):
        env.step({**all_stop(env), "t_9": 0})
    with pytest.raises(ValueError, match=r"not in 0\.\.8"):
        env.step({**all_stop(env), "t_0": 9})
    with pytest.raises(ValueError, match="an int"):
        env.step({**all_stop(env), "t_0": 1.5})
    env.step({**all_stop(env), "t_0": np.int64(8)})  # numpy ints are fine


def test_bad_construction_is_refused() -> None:
    with pytest.raises(ValueError, match="mover"):
        DecoyParallelEnv(mover="teleport")
    with pytest.raises(ValueError, match="n_t"):
        DecoyParallelEnv(n_t=-1)
    with pytest.raises(ValueError, match="at least one agent"):
        DecoyParallelEnv(n_t=0, n_ct=0)
    with pytest.raises(ValueError, match="spawn waypoints"):
        DecoyParallelEnv(n_ct=1000)
    with pytest.raises(ValueError, match="weapon"):
        DecoyParallelEnv(weapons={"T": "Banana"})
    with pytest.raises(ValueError, match="keyed by side"):
        DecoyParallelEnv(weapons={"terrorists": "AK-47"})
    for stop in (0, 1e-9, float("nan"), float("inf")):  # a STOP lasts at least a tick
        with pytest.raises(ValueError, match="stop_seconds"):
            DecoyParallelEnv(stop_seconds=stop)
    with pytest.raises(ValueError, match="render_mode"):
        DecoyParallelEnv(render_mode="human")


def test_weapons_by_side_and_by_agent() -> None:
    env = DecoyParallelEnv(n_t=2, n_ct=2, weapons={"T": "AK-47", "ct_1": "AWP"})
    env.reset(seed=0)
    assert env.sim.agents.weapon.tolist() == ["AK-47", "AK-47", "USP-S", "AWP"]
    env.close()


# ---- round ends -------------------------------------------------------------------------------


def test_random_round_ends_with_a_valid_outcome(env: DecoyParallelEnv) -> None:
    rng = np.random.default_rng(11)
    obs, _ = env.reset(seed=11)
    steps = 0
    while env.agents:
        live = list(env.agents)
        obs, rewards, terminations, truncations, infos = env.step(
            random_actions(obs, env.agents, rng)
        )
        steps += 1
        assert set(rewards) == set(terminations) == set(truncations) == set(infos) == set(live)
        assert not any(truncations.values())
    assert env.sim.done and env.sim.tick <= RULES.round_ticks + RULES.bomb_ticks
    info = infos["t_0"]
    assert END_REASONS[info["reason"]] == info["winner"] == env.sim.outcome.winner
    assert all(terminations.values())
    for name, reward in rewards.items():
        assert reward == (1.0 if name.startswith(info["winner"].lower() + "_") else -1.0)
    assert steps > 100
    if info["reason"] == "TargetSaved":  # the usual end: no plant, the clock ran out
        assert env.sim.tick == RULES.round_ticks
        assert entry(env, obs, "t_0", "round_time_left")[0] == 0.0
    env.step({})  # after the end: nothing left to do
    assert env.agents == []


def test_stop_plants_in_a_site_and_the_bomb_explodes(env: DecoyParallelEnv) -> None:
    graph = env.graph
    site_a = graph.region_of("bombsite_a")
    in_zone = site_a[SiteZones.from_graph(graph).site_of(graph.positions[site_a]) == "A"]
    obs, _ = env.reset(seed=2)
    carrier = env.sim.bomb.carrier
    env.sim.relocate(carrier, int(in_zone[0]))
    name = env.possible_agents[carrier]
    planted_at = None
    rewards: dict[str, float] = {}
    while env.agents:
        obs, rewards, _, _, infos = env.step(all_stop(env))
        state = entry(env, obs, name, "bomb_state")
        if planted_at is None and state[BOMB_STATES.index("planted")]:
            planted_at = env.sim.tick
            assert entry(env, obs, name, "bomb_site").tolist() == [1.0, 0.0]
            assert entry(env, obs, name, "has_bomb")[0] == 0.0
            frozen = entry(env, obs, name, "round_time_left")[0]
            assert 0.0 < entry(env, obs, name, "bomb_time_left")[0] < 1.0
        elif planted_at is None:
            progress = entry(env, obs, name, "plant_progress")[0]
            assert progress == pytest.approx((env.sim.tick - 1) / RULES.plant_ticks, abs=1e-6)
    assert planted_at == 210  # plant begins at tick 1, ends at 193; seen after 7 STOPs
    assert infos[name]["reason"] == "TargetBombed"
    assert env.sim.outcome.tick == 1 + RULES.plant_ticks + RULES.bomb_ticks
    assert entry(env, obs, name, "round_time_left")[0] == frozen
    assert rewards == {a: 1.0 if a.startswith("t_") else -1.0 for a in env.possible_agents}


class ShootsFirstT:
    """Test damage model: every attacker that sees agent 0 (t_0) kills it; nobody else is hit."""

    def __call__(self, batch: CombatBatch, rng: np.random.Generator) -> DamageResult:
        hit = batch.victim == 0
        return DamageResult(
            damage=np.where(hit, 100, 0),
            hit_group=np.where(hit, HIT_GROUPS.index("Chest"), -1),
            hit=hit,
        )


def test_a_dead_agent_terminates_and_leaves() -> None:
    env = DecoyParallelEnv(n_t=2, n_ct=1, damage_model=ShootsFirstT())
    env.reset(seed=1)
    graph = env.graph
    node = env.sim.agents.node[0]
    beside = graph.edge_target[graph.out_edges[node][graph.out_edges[node] >= 0][0]]
    env.sim.relocate(2, int(beside))  # ct_0 next to t_0
    carrier = env.sim.bomb.carrier
    obs, rewards, terminations, _, _ = env.step(all_stop(env))
    assert env.sim.tick == 30  # the first combat step
    assert terminations == {"t_0": True, "t_1": False, "ct_0": False}
    assert rewards == {"t_0": 0.0, "t_1": 0.0, "ct_0": 0.0}
    assert env.agents == ["t_1", "ct_0"]
    assert entry(env, obs, "t_0", "hp")[0] == 0.0
    assert entry(env, obs, "ct_0", "enemies")[:5].tolist() == [0.0] * 5  # t_0's slot: dead
    assert entry(env, obs, "ct_0", "enemies")[5] == 1.0  # t_1 alive
    if carrier == 0:
        assert entry(env, obs, "t_1", "bomb_state")[BOMB_STATES.index("dropped")] == 1.0
    obs, *_ = env.step(all_stop(env))
    assert set(obs) == {"t_1", "ct_0"}
    env.close()


def test_no_bomb() -> None:
    env = DecoyParallelEnv(n_t=2, n_ct=2, bomb=False)
    obs, _ = env.reset(seed=0)
    for name in env.possible_agents:
        assert entry(env, obs, name, "bomb_state")[0] == 1.0
        assert entry(env, obs, name, "has_bomb")[0] == 0.0
        assert entry(env, obs, name, "bomb_offset").tolist() == [0.0] * 3
    env.close()


# ---- pybullet, rendering ----------------------------------------------------------------------


def test_physics_mover_is_seeded_and_releases_its_client() -> None:
    env = DecoyParallelEnv(mover="physics")
    first = run_random(env, seed=21, steps=100)
    physics = env.physics
    assert physics is not None and pybullet.isConnected(physics.client)
    bodies = pybullet.getNumBodies(physicsClientId=physics.client)
    second = run_random(env, seed=21, steps=100)  # re-reset: the same client, fresh bodies
    assert env.physics is physics
    assert pybullet.getNumBodies(physicsClientId=physics.client) == bodies
    assert all(np.array_equal(a, b) for a, b in zip(first, second, strict=True))
    client = env.physics.client
    env.close()
    assert env.physics is None and not pybullet.isConnected(client)
    env.close()  # idempotent
    with pytest.raises(RuntimeError, match="reset"):
        env.step({})
    env.reset(seed=0)  # usable again after close
    assert pybullet.isConnected(env.physics.client)
    env.close()


def test_close_is_idempotent_without_physics(env: DecoyParallelEnv) -> None:
    env.close()
    env.reset(seed=0)
    assert env.physics is None
    env.close()
    env.close()
    assert env.agents == [] and env.sim is None


def test_render_rgb_array() -> None:
    env = DecoyParallelEnv(n_t=2, n_ct=2, render_mode="rgb_array")
    obs, _ = env.reset(seed=0)
    first = env.render()
    assert first.shape == (512, 512, 3) and first.dtype == np.uint8
    rng = np.random.default_rng(0)
    for _ in range(20):
        obs, *_ = env.step(random_actions(obs, env.agents, rng))
    assert not np.array_equal(env.render(), first)
    env.close()
    quiet = DecoyParallelEnv(n_t=1, n_ct=1)
    quiet.reset(seed=0)
    with pytest.warns(UserWarning, match="render_mode"):
        assert quiet.render() is None
    quiet.close()
