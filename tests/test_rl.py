"""Training at scale: the picklable environment factory, RLlib's adapter, and the PPO example
(`examples/rllib_ppo.py`) run for two tiny iterations on a local Ray."""

from __future__ import annotations

import pickle
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from decoy_cli.rl.factory import env_from_config

EXAMPLE = Path(__file__).resolve().parents[1] / "examples" / "rllib_ppo.py"


def test_the_factory_builds_the_environment_from_plain_settings() -> None:
    settings = {"n_t": 2, "n_ct": 3, "mover": "kinematic", "models": "none", "bomb": False}
    assert pickle.loads(pickle.dumps(env_from_config)) is env_from_config
    env = env_from_config(settings)
    assert env.possible_agents == ["t_0", "t_1", "ct_0", "ct_1", "ct_2"]
    assert env.damage_model is None and env.bomb is False
    env.close()
    with pytest.raises(ValueError, match=r"unknown environment settings \['movers'\]"):
        env_from_config({"movers": "physics"})


def test_rllib_sees_only_the_agents_that_decide_and_every_ending() -> None:
    pytest.importorskip("ray.rllib", reason="needs Ray RLlib: pip install -e '.[rl]'")
    from decoy_cli.rl.rllib_env import DecoyRLlibEnv

    env = DecoyRLlibEnv({"models": "none", "n_t": 2, "n_ct": 2})
    obs, infos = env.reset(seed=3)
    assert set(obs) == set(env.possible_agents)  # everybody decides at the start
    space = env.observation_spaces["t_0"]
    assert space.contains(obs["t_0"]) and obs["t_0"]["action_mask"].dtype == np.float32
    rng = np.random.default_rng(0)
    partial = False
    while True:
        actions = {
            name: int(rng.choice(np.flatnonzero(o["action_mask"]))) for name, o in obs.items()
        }
        obs, rewards, ends, cuts, infos = env.step(actions)
        assert cuts == {"__all__": False} and set(rewards) == set(obs) == set(infos)
        assert all(infos[name]["needs_decision"] or ends[name] for name in obs)
        partial |= 0 < len(obs) < 4
        if ends["__all__"]:
            break
        assert not any(rewards.values())
    assert partial  # agents between decisions were left out
    assert set(obs) == set(env.possible_agents)
    assert {info["reason"] for info in infos.values()} == {"TargetSaved"}
    assert all(rewards[n] == (1.0 if n.startswith("ct") else -1.0) for n in obs)
    env.close()


def test_the_ppo_example_trains_two_tiny_iterations(tmp_path: Path) -> None:
    pytest.importorskip("ray.rllib", reason="needs Ray RLlib: pip install -e '.[rl]'")
    args = ["--iterations", "2", "--env-runners", "0", "--batch", "200", "--models", "none"]
    done = subprocess.run(
        [sys.executable, str(EXAMPLE), *args],
        cwd=tmp_path,
        capture_output=True,
        text=True,
        timeout=600,
        check=False,
    )
    assert done.returncode == 0, done.stderr[-2000:]
    rows = [line.split() for line in done.stdout.splitlines() if line.split()[:1] in (["1"], ["2"])]
    assert [row[0] for row in rows] == ["1", "2"], done.stdout
    for row in rows:
        env_steps, decisions = int(row[4]), int(row[5].replace(",", ""))
        assert env_steps >= 200 and decisions >= env_steps
        assert float(row[8].replace(",", "")) > 0  # decisions per second of sampling
