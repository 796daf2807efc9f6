"""Moving agents along waypoint-graph edges, one physics tick at a time.

The engine gives an agent a goal, one edge from the node it stands on to a neighbour, with the
edge's kind and a speed, and calls `step()` once per tick. Two movers share one interface
(`Mover`) and one edge-motion computation (`_advance`, compiled with numba):

* `KinematicMover`: no collisions. Walk and step edges move the feet along the straight 3-D
  line from node to node (the height follows the ramp or climbs the ledge) at the speed, so the
  time to cross an edge is its 3-D length over the speed, the length the replay planner uses.
  A jump rises in place with CS:GO's jump speed and gravity to the upper floor's height (a
  crouch-jump, modelled as a stronger start, where the top is above a plain jump), then moves
  horizontally. A drop moves horizontally at the upper height to above the target, then falls
  with gravity. These are the paths the waypoint builder verified a capsule along
  (`decoy_cli.waypoints.lattice`), so an agent on its edge never enters a wall.
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
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Protocol

import numpy as np
from numba import njit

from decoy_cli.csgo import GRAVITY_M_S2, HAMMER_TO_M, JUMP_SPEED_M_S, PLAYER_HEIGHT_M, TICK_RATE
from decoy_cli.waypoints.graph import EdgeKind
from decoy_cli.waypoints.lattice import LatticeParams
from decoy_cli.weapons import KNIFE_SPEED
from decoy_cli.world.physics import AGENT_GROUP, WORLD_GROUP, PhysicsWorld

ARRIVE_XY_M = 0.05
"""A held-back physics agent this close to its node horizontally has arrived..."""
ARRIVE_Z_M = 0.3
"""...if its feet are also this close vertically (3-D: a cell may hold two floors)."""
DEFAULT_MAX_SPEED_M_S = KNIFE_SPEED * HAMMER_TO_M
"""Per-agent speed cap unless told otherwise: the knife, the fastest a CS:GO player runs."""
LOOKAHEAD_M = 0.3
"""An agent pushed off its edge steers to the edge point this far ahead of its own projection."""
ON_LINE_M = 0.01
"""An agent within this horizontal distance of its edge line is on it."""

# Motion phases of an agent (numba-compiled code compares these plain ints).
_IDLE, _RISE, _LINE, _GLIDE, _FALL = 0, 1, 2, 3, 4
_EPS = 1e-9

# Per-agent state is packed into a few arrays, so a compiled tick costs one call with few
# arguments (each array argument costs about 70 ns to pass; with two agents that matters).
# Columns of the float state `fv` (N, 6):
_VZ, _SPEED, _CARRY, _HEADING, _MAX_SPEED, _SIDE = range(6)
# Columns of the int state `iv` (N, 8): phase, alive (0/1), ticks of recovery left, ticks of its
# wait, consecutive blocked ticks, sidesteps on this edge, stuck events, teleports.
_PHASE, _ALIVE, _RECOVER, _WAIT, _BLOCKED, _ATTEMPTS, _STUCK, _TELEPORTS = range(8)
# Physics scratch: float `sf` (N, 2) and int `si` (N, 4) columns of a proposed move.
_P_VZ, _P_LEFT = range(2)
_P_PHASE, _P_ARRIVED, _P_MODIFIED, _P_BLOCKER = range(4)
# Rows of the per-tick flags (4, N), the arrays of `MoveStep`.
_ARRIVED, _MOVING, _STUCK_NOW, _TELEPORTED = range(4)
# Entries of the parameter vector.
(
    _DT,
    _GRAVITY,
    _LOOKAHEAD,
    _ON_LINE,
    _TWO_R,
    _CAP_LEN,
    _SIDESTEP_SPEED,
    _ARRIVE_XY,
    _ARRIVE_Z,
    _OCCUPIED_TOL,
    _STUCK_TICKS,
    _MAX_SIDESTEPS,
    _SIDESTEP_TICKS,
) = range(13)


@dataclass(slots=True)
class MoveStep:
    """What happened to each agent in one tick; every array has one row per agent."""

    arrived: np.ndarray  # bool: reached its goal this tick (then it stands still)
    moving: np.ndarray  # bool: its feet moved this tick
    stuck: np.ndarray  # bool: newly declared stuck this tick (a recovery starts)
    teleported: np.ndarray  # bool: the last-resort recovery put it on its goal this tick


class Mover(Protocol):
    """Moves agents along waypoint edges; see the module docstring."""

    def reset(self, positions: np.ndarray, max_speed: np.ndarray | float | None = None) -> None:
        """Start over with agents standing at `positions` (N, 3) (waypoints), no goals."""
        ...

    def set_goal(self, agent: int, target: np.ndarray, kind: int, speed: float) -> None:
        """Move `agent` from its node to `target` (3,) across an edge of `kind` at `speed`."""
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
        """Advance every agent by one tick."""
        ...

    @property
    def positions(self) -> np.ndarray: ...

    @property
    def heading(self) -> np.ndarray: ...

    @property
    def stuck_events(self) -> np.ndarray: ...

    @property
    def recoveries(self) -> np.ndarray: ...


# ---- the shared edge motion (numba) ---------------------------------------------------------


@njit(cache=True)
def _line_z(x, y, sx, sy, sz, tx, ty, tz):
    """Height of the straight edge line above the projection of (x, y) onto it."""
    dx, dy = tx - sx, ty - sy
    seg2 = dx * dx + dy * dy
    if seg2 <= _EPS * _EPS:
        return tz
    u = min(1.0, max(0.0, ((x - sx) * dx + (y - sy) * dy) / seg2))
    return sz + u * (tz - sz)


@njit(cache=True)
def _advance(x, y, z, sx, sy, sz, tx, ty, tz, phase, vz, speed, t, gravity, lookahead, on_line):
    """Move one agent for `t` seconds along its edge from node (sx, sy, sz) to (tx, ty, tz).

    Phases: RISE (jump: vertical, gravity, until the target height), LINE (walk/step: along the
    3-D line at `speed`), GLIDE (jump/drop: horizontal at constant height at `speed`), FALL
    (gravity, until the target height). An agent off its line (pushed aside by another) steers
    back to it, `lookahead` ahead of its projection. Returns (x, y, z, phase, vz, seconds left,
    arrived); the seconds left are those after arriving.
    """
    for _ in range(4):  # at most RISE -> GLIDE -> FALL -> landed in one call
        if phase == _RISE:
            disc = max(0.0, vz * vz - 2.0 * gravity * (tz - z))
            rise_t = (vz - math.sqrt(disc)) / gravity
            if rise_t <= t:
                z, t, vz, phase = tz, t - rise_t, 0.0, _GLIDE
                continue
            z += vz * t - 0.5 * gravity * t * t
            vz -= gravity * t
            return x, y, z, phase, vz, 0.0, False
        if phase in (_LINE, _GLIDE):
            dx, dy = tx - sx, ty - sy
            seg2 = dx * dx + dy * dy
            h_speed = speed
            if phase == _LINE and seg2 > 0.0:
                h_speed = speed * math.sqrt(seg2 / (seg2 + (tz - sz) ** 2))
            if h_speed <= 0.0:
                return x, y, z, phase, vz, 0.0, False
            ax, ay, to_target = tx, ty, True
            if seg2 > _EPS * _EPS:
                u = min(1.0, max(0.0, ((x - sx) * dx + (y - sy) * dy) / seg2))
                off = math.hypot(x - (sx + u * dx), y - (sy + u * dy))
                if off > on_line:
                    ua = u + lookahead / math.sqrt(seg2)
                    if ua < 1.0:
                        ax, ay, to_target = sx + ua * dx, sy + ua * dy, False
            ex, ey = ax - x, ay - y
            dist = math.hypot(ex, ey)
            reach = h_speed * t
            if to_target and dist <= reach + _EPS:
                x, y = tx, ty
                t = max(0.0, t - dist / h_speed)
                if phase == _GLIDE and z > tz + _EPS:
                    phase, vz = _FALL, 0.0
                    continue
                return x, y, tz, _IDLE, 0.0, t, True
            if dist > 0.0:
                frac = min(reach, dist) / dist
                x += ex * frac
                y += ey * frac
            if phase == _LINE:
                z = _line_z(x, y, sx, sy, sz, tx, ty, tz)
            return x, y, z, phase, vz, 0.0, False
        if phase == _FALL:
            land_t = (vz + math.sqrt(vz * vz + 2.0 * gravity * max(0.0, z - tz))) / gravity
            if land_t <= t:
                return x, y, tz, _IDLE, 0.0, t - land_t, True
            z += vz * t - 0.5 * gravity * t * t
            vz -= gravity * t
            return x, y, z, phase, vz, 0.0, False
        break
    return x, y, z, phase, vz, 0.0, False


@njit(cache=True)
def _move_to(i, x, y, z, pos, fv, flags):
    """Put agent i at (x, y, z); update its heading and moving flag from the displacement."""
    dx, dy, dz = x - pos[i, 0], y - pos[i, 1], z - pos[i, 2]
    if dx * dx + dy * dy > 1e-18:
        fv[i, _HEADING] = math.degrees(math.atan2(dy, dx))
    flags[_MOVING, i] = dx != 0.0 or dy != 0.0 or dz != 0.0
    pos[i, 0], pos[i, 1], pos[i, 2] = x, y, z


@njit(cache=True)
def _propose(i, pos, start, target, fv, iv, prm):
    """The shared edge motion of agent i for this tick (plus time carried from its arrival)."""
    return _advance(
        pos[i, 0], pos[i, 1], pos[i, 2], start[i, 0], start[i, 1], start[i, 2],
        target[i, 0], target[i, 1], target[i, 2], iv[i, _PHASE], fv[i, _VZ], fv[i, _SPEED],
        prm[_DT] + fv[i, _CARRY], prm[_GRAVITY], prm[_LOOKAHEAD], prm[_ON_LINE],
    )  # fmt: skip


@njit(cache=True)
def _kinematic_step(pos, start, target, fv, iv, flags, prm):
    """One tick of the kinematic mover for all agents (no collisions)."""
    for i in range(pos.shape[0]):
        if iv[i, _PHASE] == _IDLE:
            fv[i, _CARRY] = 0.0
            continue
        x, y, z, ph, v, left, arr = _propose(i, pos, start, target, fv, iv, prm)
        _move_to(i, x, y, z, pos, fv, flags)
        iv[i, _PHASE], fv[i, _VZ] = ph, v
        fv[i, _CARRY] = left if arr else 0.0
        if arr:
            flags[_ARRIVED, i] = True
            start[i, 0], start[i, 1], start[i, 2] = target[i, 0], target[i, 1], target[i, 2]


# ---- the physics mover's collision pass (numba) ---------------------------------------------


@njit(cache=True)
def _first_blocker(i, cx, cy, cz, ox, oy, oz, res, iv, two_r, cap_len):
    """First agent that agent i's capsule at (cx, cy, cz) would overlap more than it does now
    at (ox, oy, oz), against the agents' positions in `res`; -1 if none.

    Capsules are upright, so two overlap where their heights overlap and their centres are
    closer than two radii horizontally. A move out of an overlap (or along it) is allowed, so
    agents that start overlapped separate instead of locking.
    """
    two_r2 = two_r * two_r
    for j in range(res.shape[0]):
        if j == i or iv[j, _ALIVE] == 0:
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


@njit(cache=True)
def _physics_resolve(pos, start, target, fv, iv, prop, res, sf, si, need_world, flags, prm):
    """Propose every agent's move (the shared edge motion, or a recovery sidestep), then resolve
    agent-agent overlaps in index order against the already resolved positions (slide along
    the blocker, else wait). Returns how many agents ended off their verified edge line (their
    indices in `need_world`): only those need a test against the world. When none does, the
    moves are committed here, saving a second call."""
    n = pos.shape[0]
    dt, two_r, cap_len = prm[_DT], prm[_TWO_R], prm[_CAP_LEN]
    for i in range(n):
        prop[i, 0], prop[i, 1], prop[i, 2] = pos[i, 0], pos[i, 1], pos[i, 2]
        si[i, _P_PHASE], si[i, _P_ARRIVED], si[i, _P_MODIFIED] = iv[i, _PHASE], 0, 0
        si[i, _P_BLOCKER] = -1
        sf[i, _P_VZ], sf[i, _P_LEFT] = fv[i, _VZ], 0.0
        if iv[i, _ALIVE] == 0 or iv[i, _PHASE] == _IDLE:
            fv[i, _CARRY] = 0.0  # time carried from an arrival lasts one tick
            continue
        if iv[i, _RECOVER] > iv[i, _WAIT]:  # sidestep first, then wait
            ux, uy = target[i, 0] - pos[i, 0], target[i, 1] - pos[i, 1]
            norm = math.hypot(ux, uy)
            if norm > 0.0:
                speed = min(prm[_SIDESTEP_SPEED], fv[i, _MAX_SPEED])
                step = speed * dt * fv[i, _SIDE] / norm
                x, y = pos[i, 0] + uy * step, pos[i, 1] - ux * step  # right of the goal
                z = pos[i, 2]
                if iv[i, _PHASE] == _LINE:
                    z = _line_z(x, y, start[i, 0], start[i, 1], start[i, 2],
                                target[i, 0], target[i, 1], target[i, 2])  # fmt: skip
                prop[i, 0], prop[i, 1], prop[i, 2] = x, y, z
            continue
        if iv[i, _RECOVER] > 0:
            continue
        x, y, z, ph, v, left, arr = _propose(i, pos, start, target, fv, iv, prm)
        prop[i, 0], prop[i, 1], prop[i, 2] = x, y, z
        si[i, _P_PHASE], si[i, _P_ARRIVED] = ph, arr
        sf[i, _P_VZ], sf[i, _P_LEFT] = v, left

    res[:] = pos
    for i in range(n):
        if iv[i, _ALIVE] == 0:
            continue
        px, py, pz = prop[i, 0], prop[i, 1], prop[i, 2]
        ox, oy, oz = pos[i, 0], pos[i, 1], pos[i, 2]
        if px == ox and py == oy and pz == oz:
            continue
        if iv[i, _PHASE] in (_RISE, _FALL):  # in the air: passes over or lands anyway
            res[i, 0], res[i, 1], res[i, 2] = px, py, pz
            continue
        j = _first_blocker(i, px, py, pz, ox, oy, oz, res, iv, two_r, cap_len)
        if j < 0:
            res[i, 0], res[i, 1], res[i, 2] = px, py, pz
            continue
        si[i, _P_MODIFIED] = 1
        si[i, _P_BLOCKER] = j
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
        if iv[i, _PHASE] == _LINE:
            cz = _line_z(cx, cy, start[i, 0], start[i, 1], start[i, 2],
                         target[i, 0], target[i, 1], target[i, 2])  # fmt: skip
        if _first_blocker(i, cx, cy, cz, ox, oy, oz, res, iv, two_r, cap_len) < 0:
            res[i, 0], res[i, 1], res[i, 2] = cx, cy, cz

    count = 0
    for i in range(n):
        x, y = res[i, 0], res[i, 1]
        if iv[i, _ALIVE] == 0 or (x == pos[i, 0] and y == pos[i, 1]):
            continue
        dx, dy = target[i, 0] - start[i, 0], target[i, 1] - start[i, 1]
        seg2 = dx * dx + dy * dy
        u = 0.0
        if seg2 > 0.0:
            u = min(1.0, max(0.0, ((x - start[i, 0]) * dx + (y - start[i, 1]) * dy) / seg2))
        if math.hypot(x - start[i, 0] - u * dx, y - start[i, 1] - u * dy) > prm[_ON_LINE]:
            need_world[count] = i
            count += 1
    if count == 0:
        _physics_commit(pos, start, target, fv, iv, prop, res, sf, si, flags, prm)
    return count


@njit(cache=True)
def _physics_commit(pos, start, target, fv, iv, prop, res, sf, si, flags, prm):
    """Apply the resolved moves: arrivals (exact, within tolerance, or next to an agent that
    stands on the goal), progress and stuck detection, and the bounded recovery."""
    two_r, arrive_z = prm[_TWO_R], prm[_ARRIVE_Z]
    for i in range(pos.shape[0]):
        if iv[i, _ALIVE] == 0 or iv[i, _PHASE] == _IDLE:
            continue
        recovering = iv[i, _RECOVER] > 0
        if recovering:
            iv[i, _RECOVER] -= 1
        ox, oy, oz = pos[i, 0], pos[i, 1], pos[i, 2]
        tx, ty, tz = target[i, 0], target[i, 1], target[i, 2]
        if si[i, _P_MODIFIED] == 0:
            x, y, z = prop[i, 0], prop[i, 1], prop[i, 2]
            ph, v, left, arr = si[i, _P_PHASE], sf[i, _P_VZ], sf[i, _P_LEFT], si[i, _P_ARRIVED]
        else:
            x, y, z = res[i, 0], res[i, 1], res[i, 2]
            ph, v, left, arr = iv[i, _PHASE], fv[i, _VZ], 0.0, 0
            if ph in (_LINE, _GLIDE) and abs(z - tz) <= arrive_z:
                d_xy = math.hypot(x - tx, y - ty)
                j = si[i, _P_BLOCKER]
                if d_xy <= prm[_ARRIVE_XY]:
                    arr = 1
                elif j >= 0 and abs(res[j, 2] - tz) <= arrive_z:
                    gap = math.hypot(res[j, 0] - tx, res[j, 1] - ty)
                    if gap < two_r and d_xy <= two_r - gap + prm[_OCCUPIED_TOL]:
                        arr = 1
            if arr:
                ph, v = _IDLE, 0.0
        _move_to(i, x, y, z, pos, fv, flags)
        iv[i, _PHASE], fv[i, _VZ] = ph, v
        fv[i, _CARRY] = left if arr else 0.0
        if arr:
            flags[_ARRIVED, i] = True
            start[i, 0], start[i, 1], start[i, 2] = tx, ty, tz
            continue
        if recovering:
            continue
        d_old = math.sqrt((ox - tx) ** 2 + (oy - ty) ** 2 + (oz - tz) ** 2)
        want = d_old - math.sqrt(
            (prop[i, 0] - tx) ** 2 + (prop[i, 1] - ty) ** 2 + (prop[i, 2] - tz) ** 2
        )
        got = d_old - math.sqrt((x - tx) ** 2 + (y - ty) ** 2 + (z - tz) ** 2)
        if want > _EPS and got < 0.1 * want:
            iv[i, _BLOCKED] += 1
        else:
            iv[i, _BLOCKED] = 0
        if iv[i, _BLOCKED] < prm[_STUCK_TICKS]:
            continue
        flags[_STUCK_NOW, i] = True
        iv[i, _STUCK] += 1
        iv[i, _ATTEMPTS] += 1
        iv[i, _BLOCKED] = 0
        if iv[i, _ATTEMPTS] > prm[_MAX_SIDESTEPS]:  # the last resort
            _move_to(i, tx, ty, tz, pos, fv, flags)
            iv[i, _PHASE], fv[i, _VZ], fv[i, _CARRY] = _IDLE, 0.0, 0.0
            start[i, 0], start[i, 1], start[i, 2] = tx, ty, tz
            flags[_ARRIVED, i] = True
            flags[_TELEPORTED, i] = True
            iv[i, _TELEPORTS] += 1
            iv[i, _ATTEMPTS] = 0
        else:
            iv[i, _RECOVER] = int(prm[_SIDESTEP_TICKS]) + iv[i, _WAIT]
            fv[i, _SIDE] = 1.0 if iv[i, _ATTEMPTS] % 2 == 1 else -1.0


# ---- the movers -----------------------------------------------------------------------------


class _MoverBase:
    """State and goal handling shared by both movers (one row per agent in every array)."""

    def __init__(self, tick_rate: int = TICK_RATE) -> None:
        if tick_rate <= 0:
            raise ValueError("tick_rate must be positive")
        self.tick_rate = tick_rate
        self.dt = 1.0 / tick_rate
        self.gravity = GRAVITY_M_S2
        self.jump_speed = JUMP_SPEED_M_S
        self._params = np.zeros(13)
        self._params[[_DT, _GRAVITY, _LOOKAHEAD, _ON_LINE]] = (
            self.dt,
            self.gravity,
            LOOKAHEAD_M,
            ON_LINE_M,
        )
        self.reset(np.zeros((0, 3)))

    def reset(self, positions: np.ndarray, max_speed: np.ndarray | float | None = None) -> None:
        """Agents standing at `positions` (N, 3) with no goals; `max_speed` (m/s, per agent or
        one for all) caps every speed asked for (default: the knife speed)."""
        pos = np.asarray(positions, dtype=np.float64)
        if pos.ndim != 2 or pos.shape[1] != 3 or not np.all(np.isfinite(pos)):
            raise ValueError(f"positions must be finite (N, 3), got shape {pos.shape}")
        n = len(pos)
        cap = DEFAULT_MAX_SPEED_M_S if max_speed is None else max_speed
        try:
            caps = np.broadcast_to(np.asarray(cap, dtype=np.float64), (n,))
        except ValueError:
            raise ValueError(f"max_speed must be one number or one per agent ({n})") from None
        if not np.all(caps >= 0):
            raise ValueError("max_speed must be >= 0 m/s")
        self.n = n
        self._pos = pos.copy()
        self._start = pos.copy()  # the node the agent last reached: its edge's start
        self._target = pos.copy()
        self._fv = np.zeros((n, 6))
        self._fv[:, _MAX_SPEED] = caps
        self._fv[:, _SIDE] = 1.0
        self._iv = np.zeros((n, 8), dtype=np.int64)
        self._iv[:, _ALIVE] = 1
        self._views = {
            "positions": _read_only(self._pos),
            "heading": _read_only(self._fv[:, _HEADING]),
            "stuck_events": _read_only(self._iv[:, _STUCK]),
            "recoveries": _read_only(self._iv[:, _TELEPORTS]),
        }

    @property
    def positions(self) -> np.ndarray:
        """(N, 3) feet positions, metres (a read-only view that follows the agents)."""
        return self._views["positions"]

    @property
    def heading(self) -> np.ndarray:
        """(N,) yaw of the latest horizontal motion (or of the goal), degrees, 0 = +x, CCW."""
        return self._views["heading"]

    @property
    def stuck_events(self) -> np.ndarray:
        """(N,) how often each agent was declared stuck."""
        return self._views["stuck_events"]

    @property
    def recoveries(self) -> np.ndarray:
        """(N,) how often each agent was teleported to its goal (the last-resort recovery)."""
        return self._views["recoveries"]

    @property
    def alive(self) -> np.ndarray:
        """(N,) False for removed agents."""
        return self._iv[:, _ALIVE] != 0

    def _agent(self, agent: int, alive: bool = False) -> int:
        if not 0 <= agent < self.n:
            raise ValueError(f"no agent {agent} (there are {self.n})")
        if alive and not self._iv[agent, _ALIVE]:
            raise ValueError(f"agent {agent} was removed")
        return int(agent)

    def _airborne(self, i: int) -> bool:
        """On a jump or drop edge: rising, gliding over the gap or box edge, or falling."""
        return self._iv[i, _PHASE] in (_RISE, _GLIDE, _FALL)

    def set_goal(self, agent: int, target: np.ndarray, kind: int, speed: float) -> None:
        """Cross the edge from the agent's node to `target` (3,) at `speed` m/s (capped by its
        max speed); the edge `kind` (EdgeKind) chooses walking, jumping or dropping."""
        i = self._agent(agent, alive=True)
        goal = np.asarray(target, dtype=np.float64).reshape(-1)
        if goal.shape != (3,) or not np.all(np.isfinite(goal)):
            raise ValueError(f"target must be a finite (3,) position, got {target!r}")
        if not (math.isfinite(speed) and speed >= 0.0):
            raise ValueError(f"speed must be a finite number >= 0 m/s, got {speed!r}")
        kind = EdgeKind(kind)
        if self._airborne(i):
            raise ValueError(f"agent {i} is in the air; give it a goal once it lands")
        self._target[i] = goal
        fv, iv = self._fv, self._iv
        fv[i, _SPEED] = min(float(speed), fv[i, _MAX_SPEED])
        fv[i, _VZ] = 0.0
        z = self._pos[i, 2]
        if kind == EdgeKind.JUMP and goal[2] > z + _EPS:
            iv[i, _PHASE] = _RISE
            fv[i, _VZ] = max(self.jump_speed, math.sqrt(2.0 * self.gravity * (goal[2] - z)))
        elif kind in (EdgeKind.JUMP, EdgeKind.DROP):
            iv[i, _PHASE] = _GLIDE
        else:
            iv[i, _PHASE] = _LINE
        dx, dy = goal[0] - self._pos[i, 0], goal[1] - self._pos[i, 1]
        if dx * dx + dy * dy > 1e-18:
            fv[i, _HEADING] = math.degrees(math.atan2(dy, dx))
        iv[i, [_RECOVER, _BLOCKED, _ATTEMPTS]] = 0

    def clear_goal(self, agent: int) -> None:
        """Stand still. An agent on a jump or drop edge cannot stop in the air: it lands at its
        target first, which is reported as an arrival."""
        i = self._agent(agent)
        if not self._airborne(i):
            self._iv[i, _PHASE] = _IDLE
            self._fv[i, _CARRY] = 0.0

    def remove(self, agent: int) -> None:
        """A dead agent stops where it is, for good, and no longer blocks anyone."""
        i = self._agent(agent)
        self._iv[i, _ALIVE] = 0
        self._iv[i, _PHASE] = _IDLE
        self._fv[i, [_VZ, _CARRY]] = 0.0

    def place(self, agent: int, position: np.ndarray) -> None:
        """Put an alive agent on `position` (3,) with no goal: a relocation by the caller."""
        i = self._agent(agent, alive=True)
        where = np.asarray(position, dtype=np.float64).reshape(-1)
        if where.shape != (3,) or not np.all(np.isfinite(where)):
            raise ValueError(f"position must be a finite (3,) point, got {position!r}")
        self._pos[i] = where
        self._start[i] = where
        self._iv[i, [_PHASE, _RECOVER, _BLOCKED, _ATTEMPTS]] = 0
        self._fv[i, [_VZ, _CARRY]] = 0.0

    def set_max_speed(self, agent: int, speed: float) -> None:
        """Change an agent's speed cap; it applies from its next goal."""
        i = self._agent(agent)
        if not speed >= 0.0:
            raise ValueError(f"max speed must be >= 0 m/s, got {speed!r}")
        self._fv[i, _MAX_SPEED] = float(speed)

    def _new_flags(self) -> tuple[np.ndarray, MoveStep]:
        flags = np.zeros((4, self.n), dtype=bool)
        return flags, MoveStep(
            flags[_ARRIVED], flags[_MOVING], flags[_STUCK_NOW], flags[_TELEPORTED]
        )


def _read_only(array: np.ndarray) -> np.ndarray:
    view = array.view()
    view.flags.writeable = False
    return view


class KinematicMover(_MoverBase):
    """Agents follow their edges exactly and never collide: arithmetic only, no physics engine.

    One compiled loop over the agents per tick; an agent is never stuck, so `stuck_events` and
    `recoveries` stay zero.
    """

    def step(self) -> MoveStep:
        """Advance every agent by one tick."""
        flags, out = self._new_flags()
        _kinematic_step(
            self._pos, self._start, self._target, self._fv, self._iv, flags, self._params
        )
        return out


class PhysicsMover(_MoverBase):
    """Capsule agents in pybullet that block each other, moved kinematically along their edges.

    A dynamic capsule cannot climb 0.35 m steps, so each agent's capsule floats above its feet
    (the step height plus 3 cm, as the waypoint builder verified edges) and is moved by the
    shared edge motion. Each tick:

    1. every agent proposes its move along its edge (or its recovery sidestep);
    2. agent-agent overlaps are resolved in index order against already resolved positions
       (deterministic, Gauss-Seidel): a move into another capsule slides along it, or, when the
       slide also collides, the agent waits; head-on meetings step aside to the right; moves out
       of an existing overlap are allowed; agents in the air (rising, falling) pass;
    3. only agents that ended off their edge line (slid or sidestepped) are tested against the
       world, statelessly (`getClosestPoints`, not contact manifolds, which go stale after
       teleports); a penetration deeper than `graze` cancels the move. An agent on its edge
       needs no test: the waypoint builder moved this very capsule along every edge;
    4. an agent whose distance to its goal shrank by less than a tenth of what its move asked,
       for `stuck_ticks` ticks in a row (0.5 s), is stuck (counted in `stuck_events`). Recovery
       is bounded: a sidestep of two radii, alternately right and left, then a wait (odd agents
       wait twice as long, so two agents stuck on each other do not retry in lockstep), at most
       `max_sidesteps` times per edge; then, the last resort, it is teleported onto its goal
       (counted in `recoveries`, reported in `MoveStep.teleported`).

    An agent held back next to another that stands on its goal counts as arrived (it is as close
    as a player can get). A move cancelled by the world after others were resolved against it
    can leave a brief overlap, which the agents then leave (moves out of an overlap are free).

    Collision groups: the capsules are in `AGENT_GROUP` with mask `WORLD_GROUP | AGENT_GROUP`,
    so a ray cast with `collisionFilterMask=WORLD_GROUP` (what `PhysicsWorld.ray_test` does)
    ignores them and one with `WORLD_GROUP | AGENT_GROUP` hits them; `body_ids` maps bodies to
    agents. Bodies are moved lazily: call `sync_bodies()` before casting rays that should hit
    agents. Removed agents' bodies are parked far away in no collision group: nothing hits them.
    """

    def __init__(
        self,
        physics: PhysicsWorld,
        radius: float = LatticeParams().agent_radius,
        height: float = PLAYER_HEIGHT_M,
        float_height: float = LatticeParams().step_height + LatticeParams().verify_clearance,
        graze: float = LatticeParams().graze,
        stuck_ticks: int = TICK_RATE // 2,
        max_sidesteps: int = 2,
        sidestep_ticks: int = 10,
        wait_ticks: int = 10,
        tick_rate: int = TICK_RATE,
    ) -> None:
        if not (radius > 0.0 and float_height >= 0.0 and float_height + 2 * radius <= height):
            raise ValueError("need radius > 0 and float_height + 2 * radius <= height")
        if min(stuck_ticks, sidestep_ticks) < 1 or min(max_sidesteps, wait_ticks) < 0:
            raise ValueError("stuck_ticks and sidestep_ticks must be >= 1, the others >= 0")
        self.physics = physics
        self.radius = float(radius)
        self.height = float(height)
        self.float_height = float(float_height)
        self.capsule_length = self.height - self.float_height
        self.graze = float(graze)
        self.stuck_ticks = int(stuck_ticks)
        self.max_sidesteps = int(max_sidesteps)
        self.sidestep_ticks = int(sidestep_ticks)
        self.wait_ticks = int(wait_ticks)
        self._lift = np.array([0.0, 0.0, self.float_height + self.capsule_length / 2])
        p = physics._p
        self._shape = p.createCollisionShape(
            p.GEOM_CAPSULE,
            radius=self.radius,
            height=self.capsule_length - 2 * self.radius,
            physicsClientId=physics.client,
        )
        self._bodies: list[int] = []
        super().__init__(tick_rate)
        prm = self._params
        prm[_TWO_R], prm[_CAP_LEN], prm[_ARRIVE_XY], prm[_ARRIVE_Z] = (
            2.0 * self.radius,
            self.capsule_length,
            ARRIVE_XY_M,
            ARRIVE_Z_M,
        )
        prm[_SIDESTEP_SPEED] = 2.0 * self.radius / (self.sidestep_ticks * self.dt)
        prm[_OCCUPIED_TOL] = 0.1
        prm[_STUCK_TICKS], prm[_MAX_SIDESTEPS], prm[_SIDESTEP_TICKS] = (
            self.stuck_ticks,
            self.max_sidesteps,
            self.sidestep_ticks,
        )

    def reset(self, positions: np.ndarray, max_speed: np.ndarray | float | None = None) -> None:
        super().reset(positions, max_speed)
        n = self.n
        self._iv[:, _WAIT] = self.wait_ticks * (1 + np.arange(n) % 2)
        self._prop = np.zeros((n, 3))
        self._res = np.zeros((n, 3))
        self._sf = np.zeros((n, 2))
        self._si = np.zeros((n, 4), dtype=np.int64)
        self._need_world = np.zeros(n, dtype=np.int64)
        p, client = self.physics._p, self.physics.client
        while len(self._bodies) < n:
            self._bodies.append(
                p.createMultiBody(
                    baseMass=0, baseCollisionShapeIndex=self._shape, physicsClientId=client
                )
            )
        for k, body in enumerate(self._bodies):
            if k < n:
                p.setCollisionFilterGroupMask(
                    body, -1, AGENT_GROUP, WORLD_GROUP | AGENT_GROUP, physicsClientId=client
                )
            else:
                self._park(k)
        self._synced = np.full((n, 3), np.nan)
        self.sync_bodies()
        self.world_checks = 0
        """How many agent moves were tested against the world since the reset (a cost measure)."""

    @property
    def body_ids(self) -> np.ndarray:
        """(N,) pybullet body id of each agent's capsule."""
        return np.asarray(self._bodies[: self.n], dtype=np.int64)

    def sync_bodies(self) -> None:
        """Move the pybullet bodies of alive agents to the agents' positions (only those that
        moved since the last sync); call before casting rays that should hit agents."""
        p, client = self.physics._p, self.physics.client
        changed = self.alive & np.any(self._pos != self._synced, axis=1)
        centres = self._pos + self._lift
        for k in np.flatnonzero(changed).tolist():
            p.resetBasePositionAndOrientation(
                self._bodies[k], centres[k].tolist(), (0.0, 0.0, 0.0, 1.0), physicsClientId=client
            )
        self._synced[changed] = self._pos[changed]

    def _park(self, k: int) -> None:
        p, client = self.physics._p, self.physics.client
        p.setCollisionFilterGroupMask(self._bodies[k], -1, 0, 0, physicsClientId=client)
        p.resetBasePositionAndOrientation(
            self._bodies[k],
            (0.0, 0.0, -1e6 - 10.0 * k),
            (0.0, 0.0, 0.0, 1.0),
            physicsClientId=client,
        )

    def remove(self, agent: int) -> None:
        """A dead agent stops where it is, for good; its capsule leaves the world."""
        super().remove(agent)
        self._park(int(agent))

    def close(self) -> None:
        """Take the capsules out of the physics world (one world serves many rounds)."""
        p, client = self.physics._p, self.physics.client
        if client is not None:
            for body in self._bodies:
                p.removeBody(body, physicsClientId=client)
        self._bodies = []

    def step(self) -> MoveStep:
        """Advance every agent by one tick (see the class docstring)."""
        flags, out = self._new_flags()
        args = (self._pos, self._start, self._target, self._fv, self._iv, self._prop, self._res)
        count = _physics_resolve(*args, self._sf, self._si, self._need_world, flags, self._params)
        if count:
            self._world_check(self._need_world[:count].tolist())
            _physics_commit(*args, self._sf, self._si, flags, self._params)
        return out

    def _world_check(self, agents: list[int]) -> None:
        """Cancel the moves of these agents (off their verified edge) that enter the world."""
        p, client, world = self.physics._p, self.physics.client, self.physics.body
        self.world_checks += len(agents)
        centres = self._res[agents] + self._lift
        for k, i in enumerate(agents):
            body = self._bodies[i]
            p.resetBasePositionAndOrientation(
                body, centres[k].tolist(), (0.0, 0.0, 0.0, 1.0), physicsClientId=client
            )
            self._synced[i] = self._res[i]
            points = p.getClosestPoints(body, world, 0.0, physicsClientId=client)
            if any(point[8] < -self.graze for point in points):
                self._res[i] = self._pos[i]
                self._si[i, _P_MODIFIED] = 1
