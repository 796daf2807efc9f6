"""Moving agents along waypoint-graph edges, one physics tick at a time.

The engine gives an agent a goal, one edge from the node it stands on to a neighbour, with the
edge's kind and a speed, and calls `step()` once per tick. Two movers share one interface and
state (`MoverBase`) and one edge-motion computation (`kernels.advance`, compiled with numba):

* `KinematicMover`: no collisions. Walk and step edges move the feet along the straight 3-D
  line from node to node (the height follows the ramp or climbs the ledge) at the speed, so the
  time to cross an edge is its 3-D length over the speed, the length the replay planner uses.
  A jump rises in place with CS:GO's jump speed and gravity to the upper floor's height (a
  crouch-jump, modelled as a stronger start, where the top is above a plain jump), then moves
  horizontally. Off a ledge (a drop, a jump down) the agent runs at its full speed and falls
  with gravity while it runs on to above the target, as a player keeps his speed in the air:
  the edge takes its fall time (or its run, if longer). The waypoint builder verified a capsule
  along these paths (for a drop: at the upper height to above the target, then down; at full
  speed the fall starts low enough past the ledge to stay clear of it, which
  `tests/test_sim_movement.py` checks on a sample of real drops), so an agent on its edge
  does not enter a wall. A ladder edge
  is a straight 3-D line too, climbed up or down at no more than the climbing speed
  (`LADDER_SPEED_M_S`); it passes over the ladder's lip, the one path not verified.
* `PhysicsMover`: the same motion for capsule bodies in pybullet that block each other, as
  players do in CS:GO; see its docstring for the collision rules and stuck recovery.

Time is kept exactly: an agent that reaches its node with part of a tick left carries that time
into its next edge, if the next goal comes at the next tick (as the engine gives it), so a path
of edges takes its length over the speed, not a whole tick more per edge.

Arrival is reported when the motion reaches the target. When a physics agent is held back near
its target, it counts as arrived within 0.05 m horizontally and 0.3 m vertically of the node
(`ARRIVE_XY_M`, `ARRIVE_Z_M`): in 3-D, because some lattice cells hold two floors (the lower
floor passes under a bridge; floors of one cell are at least a player height apart), and 0.3 m
vertically because the feet follow the edge line exactly and only a ramp's pursuit after a
sidestep can leave them off it by a few centimetres.

Modules: `interface` (`MoveStep`), `layout` (names of the packed state's slots), `kernels`
(the shared edge motion, numba), `base` (`MoverBase`: the interface, state and goals),
`kinematic` (`KinematicMover`), `collision` (the physics mover's agent-agent pass, numba),
`physics` (`PhysicsMover`: pybullet bodies, world tests). Import the public names from here.
"""

from __future__ import annotations

from decoy_cli.sim.movement.base import DEFAULT_MAX_SPEED_M_S, LOOKAHEAD_M, ON_LINE_M, MoverBase
from decoy_cli.sim.movement.interface import MoveStep
from decoy_cli.sim.movement.kinematic import KinematicMover
from decoy_cli.sim.movement.physics import ARRIVE_XY_M, ARRIVE_Z_M, PhysicsMover

__all__ = [
    "ARRIVE_XY_M",
    "ARRIVE_Z_M",
    "DEFAULT_MAX_SPEED_M_S",
    "LOOKAHEAD_M",
    "ON_LINE_M",
    "KinematicMover",
    "MoveStep",
    "MoverBase",
    "PhysicsMover",
]
