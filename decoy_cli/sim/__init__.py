"""The headless simulator: round state, movement, line of sight and combat, bomb rules.

Entry points: `RoundSetup` and `open_round` (decoy_cli/sim/setup.py) build a ready `Simulator`
for a round; `RunSpec` is the switches and seed every run's options share. The environments
over it live in `decoy_cli.env`. Names are imported on first use.
"""

from __future__ import annotations

from importlib import import_module
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from decoy_cli.sim.decisions import Decision
    from decoy_cli.sim.engine import Simulator
    from decoy_cli.sim.random_play import RandomPolicy
    from decoy_cli.sim.setup import RoundSetup, RunSpec, Switches, open_round

_EXPORTS = {
    "Decision": "decoy_cli.sim.decisions",
    "Simulator": "decoy_cli.sim.engine",
    "RandomPolicy": "decoy_cli.sim.random_play",
    "RoundSetup": "decoy_cli.sim.setup",
    "RunSpec": "decoy_cli.sim.setup",
    "Switches": "decoy_cli.sim.setup",
    "open_round": "decoy_cli.sim.setup",
}

__all__ = [
    "Decision",
    "RandomPolicy",
    "RoundSetup",
    "RunSpec",
    "Simulator",
    "Switches",
    "open_round",
]


def __getattr__(name: str) -> object:
    if name in _EXPORTS:
        return getattr(import_module(_EXPORTS[name]), name)
    raise AttributeError(f"module 'decoy_cli.sim' has no attribute {name!r}")
