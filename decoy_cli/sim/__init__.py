"""The headless simulator: round state, movement, line of sight and combat, bomb rules, env.

Entry points: `RoundSetup` and `open_round` (decoy_cli/sim/setup.py) build a ready `Simulator`
for a round; `DecoyArrayEnv` is the environment's game with one array per step for all agents,
`DecoyParallelEnv` the PettingZoo environment over it. They are imported on
first use, so importing one part of the simulator does not load PettingZoo or gymnasium.
"""

from __future__ import annotations

from importlib import import_module
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from decoy_cli.sim.array_env import DecoyArrayEnv
    from decoy_cli.sim.decisions import Decision
    from decoy_cli.sim.engine import Simulator
    from decoy_cli.sim.env import DecoyParallelEnv
    from decoy_cli.sim.random_play import RandomPolicy
    from decoy_cli.sim.setup import RoundSetup, open_round

_EXPORTS = {
    "DecoyArrayEnv": "decoy_cli.sim.array_env",
    "Decision": "decoy_cli.sim.decisions",
    "Simulator": "decoy_cli.sim.engine",
    "DecoyParallelEnv": "decoy_cli.sim.env",
    "RandomPolicy": "decoy_cli.sim.random_play",
    "RoundSetup": "decoy_cli.sim.setup",
    "open_round": "decoy_cli.sim.setup",
}

__all__ = [
    "Decision",
    "DecoyArrayEnv",
    "DecoyParallelEnv",
    "RandomPolicy",
    "RoundSetup",
    "Simulator",
    "open_round",
]


def __getattr__(name: str) -> Any:
    if name in _EXPORTS:
        return getattr(import_module(_EXPORTS[name]), name)
    raise AttributeError(f"module 'decoy_cli.sim' has no attribute {name!r}")
