"""Names of the slots of the movers' packed state, shared by the movers and their numba kernels.

Per-agent state lives in a few plain arrays, so that a compiled tick is one call with few
arguments (every array argument costs a little to pass, which matters with two agents). The
slots of those arrays are named here, once; the kernels and the movers use these names, never a
bare slot number. numba reads module-level ints as compile-time constants, so a name costs
nothing over a literal.

Each group counts its slots (`*_SLOTS`, `FLAG_ROWS`): the arrays are allocated with that width,
and `tests/test_sim_movement.py` checks that each group numbers its slots 0..count-1 once.
"""

from __future__ import annotations

# ---- motion phases of an agent (`iv[:, I_PHASE]`) ----
IDLE = 0  # no goal, or arrived: stands still
RISE = 1  # jump: rising with gravity to the upper floor's height
LINE = 2  # walk or step: along the straight 3-D line from node to node
GLIDE = 3  # a jump's run at its top's height, or what is left to run after a landing
FALL = 4  # off a ledge or past a jump's top: falling with gravity, running on meanwhile

EPS = 1e-9
"""Lengths and times below this are zero (metres, seconds)."""

# ---- float state `fv` (N, FLOAT_SLOTS) ----
F_VZ = 0  # vertical speed, m/s (rising or falling)
F_SPEED = 1  # speed along the current edge, m/s (already capped)
F_CARRY = 2  # seconds left over from an arrival, spent on the next edge if it starts next tick
F_HEADING = 3  # yaw of the latest horizontal motion, degrees
F_MAX_SPEED = 4  # speed cap, m/s
F_SIDE = 5  # +1 / -1: which side the next recovery sidestep goes
FLOAT_SLOTS = 6

# ---- int state `iv` (N, INT_SLOTS) ----
I_PHASE = 0  # motion phase (IDLE, RISE, ...)
I_ALIVE = 1  # 1 alive, 0 removed
I_RECOVER = 2  # ticks of recovery left (sidestep, then wait)
I_WAIT = 3  # ticks this agent waits after a sidestep
I_BLOCKED = 4  # consecutive ticks without progress
I_ATTEMPTS = 5  # sidesteps on the current edge
I_STUCK = 6  # stuck events so far
I_TELEPORTS = 7  # teleports (last-resort recoveries) so far
INT_SLOTS = 8

# ---- the physics mover's scratch: a proposed move, float `sf` and int `si` ----
S_VZ = 0  # sf: vertical speed after the proposed move
S_LEFT = 1  # sf: seconds left after an arrival
SCRATCH_FLOAT_SLOTS = 2
S_PHASE = 0  # si: phase after the proposed move
S_ARRIVED = 1  # si: the proposed move arrives
S_MODIFIED = 2  # si: the move was changed (slid, waited, cancelled by the world)
S_BLOCKER = 3  # si: the agent that blocked it, -1 if none
SCRATCH_INT_SLOTS = 4

# ---- rows of the per-tick flags (FLAG_ROWS, N): the arrays of `MoveStep` ----
R_ARRIVED = 0
R_MOVING = 1
R_STUCK = 2
R_TELEPORTED = 3
R_MOVED = 4  # moved at some tick of a glide (several ticks in one call); for one tick: R_MOVING
FLAG_ROWS = 5

# ---- the parameter vector `prm` (PARAM_SLOTS,), float64 ----
P_DT = 0  # seconds per tick
P_GRAVITY = 1  # m/s²
P_LOOKAHEAD = 2  # m: an agent off its edge steers to the edge point this far ahead
P_ON_LINE = 3  # m: within this horizontal distance of its edge line an agent is on it
P_TWO_R = 4  # m: two capsule radii (physics)
P_CAP_LEN = 5  # m: capsule length from its bottom to the head (physics)
P_SIDESTEP_SPEED = 6  # m/s: speed of a recovery sidestep (physics)
P_ARRIVE_XY = 7  # m: a held-back agent this close horizontally has arrived (physics)
P_ARRIVE_Z = 8  # m: ...if also this close vertically (physics)
P_OCCUPIED_TOL = 9  # m: slack for "as close as possible" next to an agent on the goal (physics)
P_STUCK_TICKS = 10  # ticks without progress before an agent is stuck (physics)
P_MAX_SIDESTEPS = 11  # sidesteps per edge before the last-resort teleport (physics)
P_SIDESTEP_TICKS = 12  # ticks one sidestep lasts (physics)
PARAM_SLOTS = 13
