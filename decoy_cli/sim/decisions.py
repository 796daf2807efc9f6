"""What an agent decides when it is asked (`Decision`, the engine's `Policy` returns one) and how
the round takes it (`take_decision`, compiled: the engine and the compiled stretches call it)."""

from __future__ import annotations

import math
from dataclasses import dataclass
from enum import IntEnum

from decoy_cli.compiled import njit_cached
from decoy_cli.sim.movement.kernels import begin_edge
from decoy_cli.sim.movement.layout import F_CARRY, FALL, GLIDE, I_ALIVE, I_PHASE, IDLE, RISE
from decoy_cli.waypoints.graph import STOP_ACTION


@dataclass(frozen=True)
class Decision:
    """What an agent does next: a compass move (0..7) at a speed, or STOP for `hold_ticks`.

    `speed` is m/s, capped by `max_speed` (None: the weapon's CS:GO maximum); None = full speed.
    A replay may raise the cap above the weapon's where the data shows the player moving faster
    (strafe-jumps, falls). `plant` and `defuse` say whether the agent wants to plant or defuse
    while it stands still.
    """

    action: int
    speed: float | None = None
    max_speed: float | None = None
    hold_ticks: int = 30
    plant: bool = False
    defuse: bool = False


class Taken(IntEnum):
    """How `take_decision` took a decision: as asked (STOPPED, MOVING), held like a STOP for a
    move no edge makes (NO_EDGE, which the engine records), or not at all (`REFUSED`)."""

    STOPPED = 0
    MOVING = 1
    NO_EDGE = 2
    IN_THE_AIR = 3
    REMOVED = 4
    BAD_SPEED = 5
    BAD_ACTION = 6


REFUSED = {
    Taken.IN_THE_AIR: "is in the air; give it a goal once it lands",
    Taken.REMOVED: "was removed",
    Taken.BAD_SPEED: "cannot move at a speed or cap not finite and >= 0 m/s",
    Taken.BAD_ACTION: "has no such action (0..8)",
}
"""Why the round could not take a decision, which is an error (the engine raises it)."""


@njit_cached
def take_decision(r, a, act, speed, cap, hold_ticks, plant, defuse, tick):
    """Take agent a's decision at `tick` into the round `r` (`RoundState.kernel`): it counts,
    the agent wants to plant or defuse as told and leaves a damaging drop; a STOP (or a move no
    edge makes) holds `hold_ticks`; a move starts the agent along its edge at `speed`, its cap
    first set to `cap` (m/s). The one place both the engine's decisions (`Simulator._decide`)
    and the compiled stretches' (`quiet_play.play_quiet`) are taken. Returns how (`Taken`, as an
    int: an enum costs more to return) and the change in the number of agents on a damaging
    drop."""
    r.decisions[a] += 1
    r.wants_plant[a] = plant
    r.wants_defuse[a] = defuse
    falls = 0
    if r.fall_m[a] > 0.0:
        r.fall_m[a] = 0.0
        falls = -1
    if not 0 <= act <= STOP_ACTION:
        return Taken.BAD_ACTION.value, falls
    edge = -1 if act == STOP_ACTION else r.out_edges[r.node[a], act]
    if edge < 0:
        if r.iv[a, I_PHASE] not in (RISE, GLIDE, FALL):  # one in the air lands first
            r.iv[a, I_PHASE] = IDLE
            r.fv[a, F_CARRY] = 0.0
        r.hold_until[a] = tick + hold_ticks
        if act == STOP_ACTION:
            return Taken.STOPPED.value, falls
        return Taken.NO_EDGE.value, falls
    if r.iv[a, I_ALIVE] == 0:
        return Taken.REMOVED.value, falls
    if not (math.isfinite(speed) and speed >= 0.0 and cap >= 0.0):
        return Taken.BAD_SPEED.value, falls
    goal = r.edge_target[edge]
    r.goal_node[a] = goal
    if r.edge_fall[edge] > 0.0:
        r.fall_m[a] = r.edge_fall[edge]
        falls += 1
    x, y, z = r.node_pos[goal, 0], r.node_pos[goal, 1], r.node_pos[goal, 2]
    if not begin_edge(
        a, x, y, z, r.edge_kind[edge], speed, cap, r.jump_speed, r.gravity, r.mpos, r.target,
        r.fv, r.iv,
    ):  # fmt: skip
        return Taken.IN_THE_AIR.value, falls
    return Taken.MOVING.value, falls
