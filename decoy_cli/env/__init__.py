"""The environments over the simulator, a client of `decoy_cli.sim` (which imports nothing from
here), as PettingZoo's `pursuit.py` sits over its `pursuit_base.py`.

* `DecoyArrayEnv` (array_env.py): the game with one array per step for all agents;
* `DecoyParallelEnv` (parallel.py): the PettingZoo parallel environment over it;
* the observation encoder (observation.py), the compiled environment step (step.py) and the
  top-down picture (viewer.py).

They are imported on first use, so importing one part does not load PettingZoo or gymnasium.
"""

from __future__ import annotations

from importlib import import_module
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from decoy_cli.env.array_env import DecoyArrayEnv
    from decoy_cli.env.parallel import DecoyParallelEnv

_EXPORTS = {
    "DecoyArrayEnv": "decoy_cli.env.array_env",
    "DecoyParallelEnv": "decoy_cli.env.parallel",
}

__all__ = ["DecoyArrayEnv", "DecoyParallelEnv"]


def __getattr__(name: str) -> object:
    if name in _EXPORTS:
        return getattr(import_module(_EXPORTS[name]), name)
    raise AttributeError(f"module 'decoy_cli.env' has no attribute {name!r}")
