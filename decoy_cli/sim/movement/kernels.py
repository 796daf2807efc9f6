"""The edge motion both movers share, compiled with numba: one agent along one edge per call.

`advance` is the motion itself (see the package docstring for the phases); `begin_edge` starts
an agent on an edge; `kinematic_step` is the kinematic mover's whole tick and `kinematic_glide`
several ticks in one call; `propose` and `move_to` are the pieces the physics mover's collision
pass (`collision.py`) reuses. Slots of the packed arrays are named in `layout.py`.
"""

from __future__ import annotations

import math

from decoy_cli.compiled import njit_cached
from decoy_cli.csgo import LADDER_SPEED_M_S
from decoy_cli.sim.movement.layout import (
    EPS,
    F_CARRY,
    F_HEADING,
    F_MAX_SPEED,
    F_SPEED,
    F_VZ,
    FALL,
    GLIDE,
    I_ATTEMPTS,
    I_BLOCKED,
    I_PHASE,
    I_RECOVER,
    IDLE,
    LINE,
    P_DT,
    P_GRAVITY,
    P_LOOKAHEAD,
    P_ON_LINE,
    R_ARRIVED,
    R_MOVED,
    R_MOVING,
    RISE,
)

JUMP_EDGE = 2
"""`EdgeKind.JUMP` (numba reads module ints as constants; `tests/test_sim_movement.py` checks)."""
DROP_EDGE = 3
"""`EdgeKind.DROP`."""
LADDER_EDGE = 4
"""`EdgeKind.LADDER`: climbed along its line at no more than `LADDER_SPEED_M_S`."""


@njit_cached
def line_z(x, y, sx, sy, sz, tx, ty, tz):
    """Height of the straight edge line above the projection of (x, y) onto it."""
    dx, dy = tx - sx, ty - sy
    seg2 = dx * dx + dy * dy
    if seg2 <= EPS * EPS:
        return tz
    u = min(1.0, max(0.0, ((x - sx) * dx + (y - sy) * dy) / seg2))
    return sz + u * (tz - sz)


@njit_cached
def advance(x, y, z, sx, sy, sz, tx, ty, tz, phase, vz, speed, t, gravity, lookahead, on_line):
    """Move one agent for `t` seconds along its edge from node (sx, sy, sz) to (tx, ty, tz).

    Phases: RISE (jump: vertical, gravity, until the target height), LINE (walk/step/ladder:
    along the 3-D line at `speed`), GLIDE (horizontal at constant height at `speed`: a jump's
    top, or the rest of the run after a fall landed short), FALL (gravity until the target
    height, running on towards the target meanwhile). An agent off its line (pushed aside by
    another) steers back to it, `lookahead` ahead of its projection. Returns (x, y, z, phase,
    vz, seconds left, arrived); the seconds left are those after arriving.
    """
    for _ in range(4):  # at most RISE -> GLIDE -> FALL -> landed in one call
        if phase == RISE:
            disc = max(0.0, vz * vz - 2.0 * gravity * (tz - z))
            rise_t = (vz - math.sqrt(disc)) / gravity
            if rise_t <= t:
                z, t, vz, phase = tz, t - rise_t, 0.0, GLIDE
                continue
            z += vz * t - 0.5 * gravity * t * t
            vz -= gravity * t
            return x, y, z, phase, vz, 0.0, False
        if phase in (LINE, GLIDE):
            dx, dy = tx - sx, ty - sy
            seg2 = dx * dx + dy * dy
            h_speed = speed
            if phase == LINE and seg2 > 0.0:
                h_speed = speed * math.sqrt(seg2 / (seg2 + (tz - sz) ** 2))
            if h_speed <= 0.0:
                return x, y, z, phase, vz, 0.0, False
            ax, ay, to_target = tx, ty, True
            if seg2 > EPS * EPS:
                u = min(1.0, max(0.0, ((x - sx) * dx + (y - sy) * dy) / seg2))
                off = math.hypot(x - (sx + u * dx), y - (sy + u * dy))
                if off > on_line:
                    ua = u + lookahead / math.sqrt(seg2)
                    if ua < 1.0:
                        ax, ay, to_target = sx + ua * dx, sy + ua * dy, False
            ex, ey = ax - x, ay - y
            dist = math.hypot(ex, ey)
            reach = h_speed * t
            if to_target and dist <= reach + EPS:
                x, y = tx, ty
                t = max(0.0, t - dist / h_speed)
                if phase == GLIDE and z > tz + EPS:
                    phase, vz = FALL, 0.0
                    continue
                return x, y, tz, IDLE, 0.0, t, True
            if dist > 0.0:
                frac = min(reach, dist) / dist
                x += ex * frac
                y += ey * frac
            if phase == LINE:
                z = line_z(x, y, sx, sy, sz, tx, ty, tz)
            return x, y, z, phase, vz, 0.0, False
        if phase == FALL:
            land_t = (vz + math.sqrt(vz * vz + 2.0 * gravity * max(0.0, z - tz))) / gravity
            air_t = min(t, land_t)
            ex, ey = tx - x, ty - y  # the run goes on while falling
            dist = math.hypot(ex, ey)
            over = dist <= speed * air_t + EPS
            if over:
                x, y = tx, ty
            elif dist > 0.0:
                x += ex * speed * air_t / dist
                y += ey * speed * air_t / dist
            if land_t <= t:
                if over:
                    return x, y, tz, IDLE, 0.0, t - land_t, True
                z, t, vz, phase = tz, t - land_t, 0.0, GLIDE  # landed short: run the rest
                continue
            z += vz * t - 0.5 * gravity * t * t
            vz -= gravity * t
            return x, y, z, phase, vz, 0.0, False
        break
    return x, y, z, phase, vz, 0.0, False


@njit_cached
def move_to(i, x, y, z, pos, fv, flags):
    """Put agent i at (x, y, z); update its heading and moving flag from the displacement."""
    dx, dy, dz = x - pos[i, 0], y - pos[i, 1], z - pos[i, 2]
    if dx * dx + dy * dy > 1e-18:
        fv[i, F_HEADING] = math.degrees(math.atan2(dy, dx))
    flags[R_MOVING, i] = dx != 0.0 or dy != 0.0 or dz != 0.0
    pos[i, 0], pos[i, 1], pos[i, 2] = x, y, z


@njit_cached
def propose(i, pos, start, target, fv, iv, prm):
    """The shared edge motion of agent i for this tick (plus time carried from its arrival)."""
    return advance(
        pos[i, 0], pos[i, 1], pos[i, 2], start[i, 0], start[i, 1], start[i, 2],
        target[i, 0], target[i, 1], target[i, 2], iv[i, I_PHASE], fv[i, F_VZ], fv[i, F_SPEED],
        prm[P_DT] + fv[i, F_CARRY], prm[P_GRAVITY], prm[P_LOOKAHEAD], prm[P_ON_LINE],
    )  # fmt: skip


@njit_cached
def kinematic_step(pos, start, target, fv, iv, flags, prm):
    """One tick of the kinematic mover for all agents (no collisions)."""
    for i in range(pos.shape[0]):
        if iv[i, I_PHASE] == IDLE:
            fv[i, F_CARRY] = 0.0
            continue
        x, y, z, ph, v, left, arr = propose(i, pos, start, target, fv, iv, prm)
        move_to(i, x, y, z, pos, fv, flags)
        iv[i, I_PHASE], fv[i, F_VZ] = ph, v
        fv[i, F_CARRY] = left if arr else 0.0
        if arr:
            flags[R_ARRIVED, i] = True
            start[i, 0], start[i, 1], start[i, 2] = target[i, 0], target[i, 1], target[i, 2]


@njit_cached
def kinematic_glide(pos, start, target, fv, iv, flags, prm, max_ticks):
    """Up to `max_ticks` kinematic ticks, stopping after the first tick in which an agent
    arrives; returns (ticks done, 1 if an agent arrived else 0: `MoveStep.happened`). `flags`
    hold that last tick's rows, and R_MOVED every agent that moved at any of the ticks."""
    n = pos.shape[0]
    for k in range(max_ticks):
        for i in range(n):
            flags[R_ARRIVED, i] = False
            flags[R_MOVING, i] = False
        kinematic_step(pos, start, target, fv, iv, flags, prm)
        arrived = False
        for i in range(n):
            if flags[R_MOVING, i]:
                flags[R_MOVED, i] = True
            if flags[R_ARRIVED, i]:
                arrived = True
        if arrived:
            return k + 1, 1
    return max_ticks, 0


@njit_cached
def begin_edge(i, tx, ty, tz, kind, speed, cap, jump_speed, gravity, pos, target, fv, iv):
    """Start agent i on the edge to (tx, ty, tz) of `kind` (EdgeKind) at `speed` (capped by
    its max speed, first set to `cap` unless that is negative; on a ladder, the climbing speed
    when the agent is asked for its max speed, which no weapon slows, else the speed asked up to
    it): its phase, vertical speed and heading. Returns False, changing nothing, if the agent is
    in the air (it lands first)."""
    if iv[i, I_PHASE] in (RISE, GLIDE, FALL):
        return False
    if cap >= 0.0:
        fv[i, F_MAX_SPEED] = cap
    target[i, 0], target[i, 1], target[i, 2] = tx, ty, tz
    fv[i, F_SPEED] = min(speed, fv[i, F_MAX_SPEED])
    if kind == LADDER_EDGE:  # asked for its full speed, an agent climbs at the climbing speed
        full = speed >= fv[i, F_MAX_SPEED] - EPS
        fv[i, F_SPEED] = LADDER_SPEED_M_S if full else min(speed, LADDER_SPEED_M_S)
    fv[i, F_VZ] = 0.0
    z = pos[i, 2]
    if kind == JUMP_EDGE and tz > z + EPS:
        iv[i, I_PHASE] = RISE
        fv[i, F_VZ] = max(jump_speed, math.sqrt(2.0 * gravity * (tz - z)))
    elif kind in (JUMP_EDGE, DROP_EDGE) and tz < z - EPS:
        # Off a ledge at full speed, the run going on while the agent falls (a player keeps
        # his speed in the air): at that speed he clears the ledge before he sinks below it.
        iv[i, I_PHASE] = FALL
        fv[i, F_SPEED] = fv[i, F_MAX_SPEED]
    elif kind in (JUMP_EDGE, DROP_EDGE):
        iv[i, I_PHASE] = GLIDE
    else:
        iv[i, I_PHASE] = LINE
    dx, dy = tx - pos[i, 0], ty - pos[i, 1]
    if dx * dx + dy * dy > 1e-18:
        fv[i, F_HEADING] = math.degrees(math.atan2(dy, dx))
    iv[i, I_RECOVER], iv[i, I_BLOCKED], iv[i, I_ATTEMPTS] = 0, 0, 0
    return True
