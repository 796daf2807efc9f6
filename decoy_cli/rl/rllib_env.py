"""Ray RLlib's multi-agent environment over `DecoyParallelEnv`, and a callback for win rates.

RLlib (its new API stack) asks for actions of exactly the agents in the last observation dict.
Decisions here are asynchronous (an agent decides at its waypoint or when its STOP ends), so the
adapter hands RLlib the observations of the agents that need a decision, and of every agent
whose episode ends at this step, with its final reward; an agent walking an edge or holding a
STOP is absent until it decides again. Rewards are zero until the round ends, when every agent
still in it observes, so no reward falls between decisions.

Observations are {"observations": float32 vector, "action_mask": float32 (9,)}: the keys and
type RLlib's action-masking RL module (`ActionMaskingTorchRLModule`) reads. Importing this
module needs Ray: `pip install -e ".[rl]"`.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from gymnasium import spaces
from ray.rllib.callbacks.callbacks import RLlibCallback
from ray.rllib.env.multi_agent_env import MultiAgentEnv

from decoy_cli.env.observation import NUM_ACTIONS
from decoy_cli.rl.factory import env_from_config


class DecoyRLlibEnv(MultiAgentEnv):
    """One CS:GO round per episode for RLlib; `config` holds `factory.ENV_SETTINGS`."""

    def __init__(self, config: dict[str, object] | None = None) -> None:
        super().__init__()
        self.env = env_from_config(config)
        names: list[str] = list(self.env.possible_agents)
        self.possible_agents = list(names)
        self.agents = []
        mask = spaces.Box(0.0, 1.0, (NUM_ACTIONS,), np.float32)
        self.observation_spaces = {
            name: spaces.Dict(
                {
                    "observations": self.env.observation_space(name)["observation"],
                    "action_mask": mask,
                }
            )
            for name in names
        }
        self.action_spaces = {name: self.env.action_space(name) for name in names}

    def reset(self, *, seed: int | None = None, options: dict | None = None):
        observations, infos = self.env.reset(seed=seed, options=options)
        self.agents = list(self.env.agents)
        acting = [name for name in self.env.agents if infos[name]["needs_decision"]]
        return self._observe(observations, acting), {name: infos[name] for name in acting}

    def step(self, action_dict: dict[Any, Any]):  # as MultiAgentEnv.step
        observations, rewards, ends, _, infos = self.env.step(action_dict)
        acting = [name for name in observations if infos[name]["needs_decision"] or ends[name]]
        self.agents = list(self.env.agents)
        over = not self.agents
        return (
            self._observe(observations, acting),
            {name: rewards[name] for name in acting},
            {name: ends[name] for name in acting} | {"__all__": over},
            {"__all__": False},  # the rules end every round: nothing is cut short
            {name: infos[name] for name in acting},
        )

    def close(self) -> None:
        self.env.close()

    @staticmethod
    def _observe(
        observations: dict[str, dict[str, np.ndarray]], names: list[str]
    ) -> dict[str, dict[str, np.ndarray]]:
        return {
            name: {
                "observations": observations[name]["observation"],
                "action_mask": observations[name]["action_mask"].astype(np.float32),
            }
            for name in names
        }


class WinRates(RLlibCallback):
    """Logs, per episode, whether T won (`t_win_rate`, mean over the iteration's episodes) and
    the round's length in game seconds (`round_s`)."""

    def on_episode_end(self, *, episode, metrics_logger=None, **kwargs) -> None:
        if metrics_logger is None:
            return
        last = episode.get_infos(-1)
        ended = [info for info in last.values() if isinstance(info, dict) and "winner" in info]
        if ended:
            metrics_logger.log_value("t_win_rate", float(ended[0]["winner"] == "T"), reduce="mean")
            metrics_logger.log_value("round_s", ended[0]["tick"] / 60.0, reduce="mean")
