"""The physics mover's agent-agent collision pass and its commit, compiled with numba.

`physics_resolve` proposes every agent's move and resolves overlaps between agents;
`physics_commit` applies the moves, detects arrivals and stuck agents and runs the bounded
recovery; `physics_glide` runs whole ticks of both until one needs the world or an agent
arrives, is stuck or teleported. Between the two, `PhysicsMover` tests the few agents that left
their edge line against the world. Slots of the packed arrays are named in `layout.py`.
"""

from __future__ import annotations

import math

from decoy_cli.compiled import njit_cached
from decoy_cli.sim.movement.kernels import line_z, move_to, propose
from decoy_cli.sim.movement.layout import (
    EPS,
    F_CARRY,
    F_MAX_SPEED,
    F_SIDE,
    F_VZ,
    FALL,
    GLIDE,
    I_ALIVE,
    I_ATTEMPTS,
    I_BLOCKED,
    I_PHASE,
    I_RECOVER,
    I_STUCK,
    I_TELEPORTS,
    I_WAIT,
    IDLE,
    LINE,
    P_ARRIVE_XY,
    P_ARRIVE_Z,
    P_CAP_LEN,
    P_DT,
    P_MAX_SIDESTEPS,
    P_OCCUPIED_TOL,
    P_ON_LINE,
    P_SIDESTEP_SPEED,
    P_SIDESTEP_TICKS,
    P_STUCK_TICKS,
    P_TWO_R,
    R_ARRIVED,
    R_MOVED,
    R_MOVING,
    R_STUCK,
    R_TELEPORTED,
    RISE,
    S_ARRIVED,
    S_BLOCKER,
    S_LEFT,
    S_MODIFIED,
    S_PHASE,
    S_VZ,
)


@njit_cached
def first_blocker(i, cx, cy, cz, ox, oy, oz, res, iv, two_r, cap_len):
    """First agent that agent i's capsule at (cx, cy, cz) would overlap more than it does now
    at (ox, oy, oz), against the agents' positions in `res`; -1 if none.

    Capsules are upright, so two overlap where their heights overlap and their centres are
    closer than two radii horizontally. A move out of an overlap (or along it) is allowed, so
    agents that start overlapped separate instead of locking.
    """
    two_r2 = two_r * two_r
    for j in range(res.shape[0]):
        if j == i or iv[j, I_ALIVE] == 0:
            continue
        if abs(cz - res[j, 2]) >= cap_len:
            continue
        dx, dy = cx - res[j, 0], cy - res[j, 1]
        d2 = dx * dx + dy * dy
        if d2 >= two_r2:
            continue
        if abs(oz - res[j, 2]) >= cap_len:
            return j
        ex, ey = ox - res[j, 0], oy - res[j, 1]
        if d2 < ex * ex + ey * ey - 1e-12:
            return j
    return -1


@njit_cached
def physics_resolve(pos, start, target, fv, iv, prop, res, sf, si, need_world, flags, prm):
    """Propose every agent's move (the shared edge motion, or a recovery sidestep), then resolve
    agent-agent overlaps in index order against the already resolved positions (slide along
    the blocker, else wait). Returns how many agents ended off their verified edge line (their
    indices in `need_world`): only those need a test against the world. When none does, the
    moves are committed here, saving a second call."""
    n = pos.shape[0]
    dt, two_r, cap_len = prm[P_DT], prm[P_TWO_R], prm[P_CAP_LEN]
    for i in range(n):
        prop[i, 0], prop[i, 1], prop[i, 2] = pos[i, 0], pos[i, 1], pos[i, 2]
        si[i, S_PHASE], si[i, S_ARRIVED], si[i, S_MODIFIED] = iv[i, I_PHASE], 0, 0
        si[i, S_BLOCKER] = -1
        sf[i, S_VZ], sf[i, S_LEFT] = fv[i, F_VZ], 0.0
        if iv[i, I_ALIVE] == 0 or iv[i, I_PHASE] == IDLE:
            fv[i, F_CARRY] = 0.0  # time carried from an arrival lasts one tick
            continue
        if iv[i, I_RECOVER] > iv[i, I_WAIT]:  # sidestep first, then wait
            ux, uy = target[i, 0] - pos[i, 0], target[i, 1] - pos[i, 1]
            norm = math.hypot(ux, uy)
            if norm > 0.0:
                speed = min(prm[P_SIDESTEP_SPEED], fv[i, F_MAX_SPEED])
                step = speed * dt * fv[i, F_SIDE] / norm
                x, y = pos[i, 0] + uy * step, pos[i, 1] - ux * step  # right of the goal
                z = pos[i, 2]
                if iv[i, I_PHASE] == LINE:
                    z = line_z(x, y, start[i, 0], start[i, 1], start[i, 2],
                                target[i, 0], target[i, 1], target[i, 2])  # fmt: skip
                prop[i, 0], prop[i, 1], prop[i, 2] = x, y, z
            continue
        if iv[i, I_RECOVER] > 0:
            continue
        x, y, z, ph, v, left, arr = propose(i, pos, start, target, fv, iv, prm)
        prop[i, 0], prop[i, 1], prop[i, 2] = x, y, z
        si[i, S_PHASE], si[i, S_ARRIVED] = ph, arr
        sf[i, S_VZ], sf[i, S_LEFT] = v, left

    res[:] = pos
    for i in range(n):
        if iv[i, I_ALIVE] == 0:
            continue
        px, py, pz = prop[i, 0], prop[i, 1], prop[i, 2]
        ox, oy, oz = pos[i, 0], pos[i, 1], pos[i, 2]
        if px == ox and py == oy and pz == oz:
            continue
        if iv[i, I_PHASE] in (RISE, FALL):  # in the air: passes over or lands anyway
            res[i, 0], res[i, 1], res[i, 2] = px, py, pz
            continue
        j = first_blocker(i, px, py, pz, ox, oy, oz, res, iv, two_r, cap_len)
        if j < 0:
            res[i, 0], res[i, 1], res[i, 2] = px, py, pz
            continue
        si[i, S_MODIFIED] = 1
        si[i, S_BLOCKER] = j
        mx, my = px - ox, py - oy
        m_len = math.hypot(mx, my)
        if m_len == 0.0:
            continue
        nx, ny = ox - res[j, 0], oy - res[j, 1]
        n_len = math.hypot(nx, ny)
        if n_len == 0.0:
            nx, ny = -my / m_len, mx / m_len
        else:
            nx, ny = nx / n_len, ny / n_len
        mn = mx * nx + my * ny
        sx, sy = mx - mn * nx, my - mn * ny  # the move without its part into the blocker
        if math.hypot(sx, sy) < 0.25 * m_len:
            # head-on: step aside to the right, so two agents meeting face to face both keep
            # right and pass
            tx, ty = -ny, nx
            if tx * my - ty * mx < 0.0:
                tx, ty = -tx, -ty
            sx, sy = 0.5 * m_len * tx, 0.5 * m_len * ty
        cx, cy, cz = ox + sx, oy + sy, oz
        if iv[i, I_PHASE] == LINE:
            cz = line_z(cx, cy, start[i, 0], start[i, 1], start[i, 2],
                         target[i, 0], target[i, 1], target[i, 2])  # fmt: skip
        if first_blocker(i, cx, cy, cz, ox, oy, oz, res, iv, two_r, cap_len) < 0:
            res[i, 0], res[i, 1], res[i, 2] = cx, cy, cz

    count = 0
    for i in range(n):
        x, y = res[i, 0], res[i, 1]
        if iv[i, I_ALIVE] == 0 or (x == pos[i, 0] and y == pos[i, 1]):
            continue
        dx, dy = target[i, 0] - start[i, 0], target[i, 1] - start[i, 1]
        seg2 = dx * dx + dy * dy
        u = 0.0
        if seg2 > 0.0:
            u = min(1.0, max(0.0, ((x - start[i, 0]) * dx + (y - start[i, 1]) * dy) / seg2))
        if math.hypot(x - start[i, 0] - u * dx, y - start[i, 1] - u * dy) > prm[P_ON_LINE]:
            need_world[count] = i
            count += 1
    if count == 0:
        physics_commit(pos, start, target, fv, iv, prop, res, sf, si, flags, prm)
    return count


@njit_cached
def physics_commit(pos, start, target, fv, iv, prop, res, sf, si, flags, prm):
    """Apply the resolved moves: arrivals (exact, within tolerance, or next to an agent that
    stands on the goal), progress and stuck detection, and the bounded recovery."""
    two_r, arrive_z = prm[P_TWO_R], prm[P_ARRIVE_Z]
    for i in range(pos.shape[0]):
        if iv[i, I_ALIVE] == 0 or iv[i, I_PHASE] == IDLE:
            continue
        recovering = iv[i, I_RECOVER] > 0
        if recovering:
            iv[i, I_RECOVER] -= 1
        ox, oy, oz = pos[i, 0], pos[i, 1], pos[i, 2]
        tx, ty, tz = target[i, 0], target[i, 1], target[i, 2]
        if si[i, S_MODIFIED] == 0:
            x, y, z = prop[i, 0], prop[i, 1], prop[i, 2]
            ph, v, left, arr = si[i, S_PHASE], sf[i, S_VZ], sf[i, S_LEFT], si[i, S_ARRIVED]
        else:
            x, y, z = res[i, 0], res[i, 1], res[i, 2]
            ph, v, left, arr = iv[i, I_PHASE], fv[i, F_VZ], 0.0, 0
            if ph in (LINE, GLIDE) and abs(z - tz) <= arrive_z:
                d_xy = math.hypot(x - tx, y - ty)
                j = si[i, S_BLOCKER]
                if d_xy <= prm[P_ARRIVE_XY]:
                    arr = 1
                elif j >= 0 and abs(res[j, 2] - tz) <= arrive_z:
                    gap = math.hypot(res[j, 0] - tx, res[j, 1] - ty)
                    if gap < two_r and d_xy <= two_r - gap + prm[P_OCCUPIED_TOL]:
                        arr = 1
            if arr:
                ph, v = IDLE, 0.0
        move_to(i, x, y, z, pos, fv, flags)
        iv[i, I_PHASE], fv[i, F_VZ] = ph, v
        fv[i, F_CARRY] = left if arr else 0.0
        if arr:
            flags[R_ARRIVED, i] = True
            start[i, 0], start[i, 1], start[i, 2] = tx, ty, tz
            continue
        if recovering:
            continue
        d_old = math.sqrt((ox - tx) ** 2 + (oy - ty) ** 2 + (oz - tz) ** 2)
        want = d_old - math.sqrt(
            (prop[i, 0] - tx) ** 2 + (prop[i, 1] - ty) ** 2 + (prop[i, 2] - tz) ** 2
        )
        got = d_old - math.sqrt((x - tx) ** 2 + (y - ty) ** 2 + (z - tz) ** 2)
        if want > EPS and got < 0.1 * want:
            iv[i, I_BLOCKED] += 1
        else:
            iv[i, I_BLOCKED] = 0
        if iv[i, I_BLOCKED] < prm[P_STUCK_TICKS]:
            continue
        flags[R_STUCK, i] = True
        iv[i, I_STUCK] += 1
        iv[i, I_ATTEMPTS] += 1
        iv[i, I_BLOCKED] = 0
        if iv[i, I_ATTEMPTS] > prm[P_MAX_SIDESTEPS]:  # the last resort
            move_to(i, tx, ty, tz, pos, fv, flags)
            iv[i, I_PHASE], fv[i, F_VZ], fv[i, F_CARRY] = IDLE, 0.0, 0.0
            start[i, 0], start[i, 1], start[i, 2] = tx, ty, tz
            flags[R_ARRIVED, i] = True
            flags[R_TELEPORTED, i] = True
            iv[i, I_TELEPORTS] += 1
            iv[i, I_ATTEMPTS] = 0
        else:
            iv[i, I_RECOVER] = int(prm[P_SIDESTEP_TICKS]) + iv[i, I_WAIT]
            fv[i, F_SIDE] = 1.0 if iv[i, I_ATTEMPTS] % 2 == 1 else -1.0


@njit_cached
def physics_glide(pos, start, target, fv, iv, prop, res, sf, si, need_world, flags, prm, ticks):
    """Up to `ticks` ticks of resolve and commit. Stops after a tick in which an agent arrives,
    is stuck or is teleported, or at a tick whose resolved moves need a world test: that tick
    is left uncommitted for the caller. Returns (ticks advanced, agents needing the world test
    at the last tick (0 if it is committed), the `MoveStep.happened` bits of the last tick: 1
    an agent arrived, 2 one was stuck, 4 one was teleported). R_MOVED collects every agent that
    moved."""
    n = pos.shape[0]
    for k in range(ticks):
        for i in range(n):
            flags[R_ARRIVED, i] = False
            flags[R_MOVING, i] = False
            flags[R_STUCK, i] = False
            flags[R_TELEPORTED, i] = False
        count = physics_resolve(pos, start, target, fv, iv, prop, res, sf, si, need_world,
                                flags, prm)  # fmt: skip
        if count:
            return k + 1, count, 0
        happened = 0
        for i in range(n):
            if flags[R_MOVING, i]:
                flags[R_MOVED, i] = True
            if flags[R_ARRIVED, i]:
                happened |= 1
            if flags[R_STUCK, i]:
                happened |= 2
            if flags[R_TELEPORTED, i]:
                happened |= 4
        if happened:
            return k + 1, 0, happened
    return ticks, 0, 0
