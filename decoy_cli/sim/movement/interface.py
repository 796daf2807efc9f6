"""The movers' interface: `Mover`, what every mover does, and `MoveStep`, what a tick did."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Protocol

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


class Mover(Protocol):
    """Moves agents along waypoint edges; see the module docstring."""

    def reset(self, positions: np.ndarray, max_speed: np.ndarray | float | None = None) -> None:
        """Start over with agents standing at `positions` (N, 3) (waypoints), no goals."""
        ...

    def set_goal(
        self,
        agent: int,
        target: np.ndarray,
        kind: int,
        speed: float,
        max_speed: float | None = None,
    ) -> None:
        """Move `agent` from its node to `target` (3,) across an edge of `kind` at `speed`
        (capped by its speed cap, first changed to `max_speed` if given)."""
        ...

    def clear_goal(self, agent: int) -> None:
        """Stand still (an agent on a jump or drop edge lands at its target first)."""
        ...

    def remove(self, agent: int) -> None:
        """A dead agent: it stops where it is and no longer collides."""
        ...

    def place(self, agent: int, position: np.ndarray) -> None:
        """Put an agent on a position (a relocation by the caller), with no goal."""
        ...

    def set_max_speed(self, agent: int, speed: float) -> None:
        """Change an agent's speed cap (for example after a weapon switch)."""
        ...

    def step(self) -> MoveStep:
        """Advance every agent by one tick. The `MoveStep` is the mover's own: the next `step`
        or `glide` overwrites it (copy what you keep)."""
        ...

    def glide(self, max_ticks: int) -> tuple[int, MoveStep]:
        """Advance up to `max_ticks` ticks in one call, stopping after the first tick in which an
        agent arrives, is declared stuck or is teleported; returns the ticks advanced and that
        last tick's `MoveStep` (`moved`: over all of them). Each tick is computed exactly as
        `step` computes it."""
        ...

    @property
    def positions(self) -> np.ndarray: ...

    def is_standing(self, agent: int) -> bool:
        """Whether the agent has no motion under way (it stays put until given a goal)."""
        ...

    @property
    def heading(self) -> np.ndarray: ...

    @property
    def stuck_events(self) -> np.ndarray: ...

    @property
    def recoveries(self) -> np.ndarray: ...
