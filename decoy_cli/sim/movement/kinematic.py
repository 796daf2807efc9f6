"""`KinematicMover`: the shared edge motion with no collisions and no physics engine."""

from __future__ import annotations

from decoy_cli.sim.movement.base import MoverBase
from decoy_cli.sim.movement.interface import MoveStep
from decoy_cli.sim.movement.kernels import kinematic_step


class KinematicMover(MoverBase):
    """Agents follow their edges exactly and never collide: arithmetic only, no physics engine.

    One compiled loop over the agents per tick; an agent is never stuck, so `stuck_events` and
    `recoveries` stay zero.
    """

    def step(self) -> MoveStep:
        """Advance every agent by one tick."""
        flags, out = self._new_flags()
        kinematic_step(
            self._pos, self._start, self._target, self._fv, self._iv, flags, self._params
        )
        return out
