"""`KinematicMover`: the shared edge motion with no collisions and no physics engine."""

from __future__ import annotations

from decoy_cli.sim.movement.base import MoverBase
from decoy_cli.sim.movement.interface import MoveStep
from decoy_cli.sim.movement.kernels import kinematic_glide


class KinematicMover(MoverBase):
    """Agents follow their edges exactly and never collide: arithmetic only, no physics engine.

    One compiled loop over the agents per tick; an agent is never stuck, so `stuck_events` and
    `recoveries` stay zero.
    """

    def glide(self, max_ticks: int) -> tuple[int, MoveStep]:
        """Up to `max_ticks` ticks in one compiled call, stopping after the first arrival."""
        flags, out = self._new_flags()
        ticks, out.happened = kinematic_glide(
            self._pos, self._start, self._target, self._fv, self._iv, flags, self._params,
            max(1, int(max_ticks)),
        )  # fmt: skip
        return int(ticks), out
