"""What a mover's tick did: `MoveStep` (what every mover does is `base.MoverBase`)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

ARRIVAL, STUCK, TELEPORT = 1, 2, 4
"""Bits of `MoveStep.happened`: some agent arrived, was declared stuck, was teleported."""


@dataclass(slots=True)
class MoveStep:
    """What happened to each agent in one tick; every array has one row per agent."""

    arrived: np.ndarray  # bool: reached its goal this tick (then it stands still)
    moving: np.ndarray  # bool: its feet moved this tick
    stuck: np.ndarray  # bool: newly declared stuck this tick (a recovery starts)
    teleported: np.ndarray  # bool: the last-resort recovery put it on its goal this tick
    moved: np.ndarray  # bool: its feet moved at some tick of the call (`glide` spans several)
    happened: int = ARRIVAL | STUCK | TELEPORT  # which of these happened to any agent (bits)
