"""State and goal handling shared by both movers: packed per-agent arrays, goals, removal."""

from __future__ import annotations

import math

import numpy as np

from decoy_cli.csgo import GRAVITY_M_S2, HAMMER_TO_M, JUMP_SPEED_M_S, TICK_RATE
from decoy_cli.sim.movement.interface import ARRIVAL, STUCK, TELEPORT, MoveStep
from decoy_cli.sim.movement.kernels import begin_edge
from decoy_cli.sim.movement.layout import (
    F_CARRY,
    F_HEADING,
    F_MAX_SPEED,
    F_SIDE,
    F_VZ,
    FALL,
    FLAG_ROWS,
    FLOAT_SLOTS,
    GLIDE,
    I_ALIVE,
    I_ATTEMPTS,
    I_BLOCKED,
    I_PHASE,
    I_RECOVER,
    I_STUCK,
    I_TELEPORTS,
    IDLE,
    INT_SLOTS,
    P_DT,
    P_GRAVITY,
    P_LOOKAHEAD,
    P_ON_LINE,
    PARAM_SLOTS,
    R_ARRIVED,
    R_MOVED,
    R_MOVING,
    R_STUCK,
    R_TELEPORTED,
    RISE,
)
from decoy_cli.waypoints.graph import EdgeKind
from decoy_cli.weapons import KNIFE_SPEED

_EDGE_KINDS = frozenset(int(kind) for kind in EdgeKind)

DEFAULT_MAX_SPEED_M_S = KNIFE_SPEED * HAMMER_TO_M
"""Per-agent speed cap unless told otherwise: the knife, the fastest a CS:GO player runs."""
LOOKAHEAD_M = 0.3
"""An agent pushed off its edge steers to the edge point this far ahead of its own projection."""
ON_LINE_M = 0.01
"""An agent within this horizontal distance of its edge line is on it."""


class MoverBase:
    """What every mover does, and the state and goal handling both share (one row per agent in
    every array); the engine works on their packed state (`kernel_arrays`)."""

    def __init__(self, tick_rate: int = TICK_RATE) -> None:
        if tick_rate <= 0:
            raise ValueError("tick_rate must be positive")
        self.tick_rate = tick_rate
        self.dt = 1.0 / tick_rate
        self.gravity = GRAVITY_M_S2
        self.jump_speed = JUMP_SPEED_M_S
        self._params = np.zeros(PARAM_SLOTS)
        self._params[[P_DT, P_GRAVITY, P_LOOKAHEAD, P_ON_LINE]] = (
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
        self._fv = np.zeros((n, FLOAT_SLOTS))
        self._fv[:, F_MAX_SPEED] = caps
        self._fv[:, F_SIDE] = 1.0
        self._iv = np.zeros((n, INT_SLOTS), dtype=np.int64)
        self._iv[:, I_ALIVE] = 1
        self._flags = flags = np.zeros((FLAG_ROWS, n), dtype=bool)
        self._out = MoveStep(
            flags[R_ARRIVED], flags[R_MOVING], flags[R_STUCK], flags[R_TELEPORTED], flags[R_MOVED]
        )
        self._views = {
            "positions": read_only(self._pos),
            "heading": read_only(self._fv[:, F_HEADING]),
            "stuck_events": read_only(self._iv[:, I_STUCK]),
            "recoveries": read_only(self._iv[:, I_TELEPORTS]),
        }

    def kernel_arrays(self) -> tuple[np.ndarray, ...]:
        """The packed state the edge kernels work on, for compiled callers that move the agents
        themselves (`decoy_cli.sim.quiet_play`, with the kinematic mover): positions, edge
        starts, targets, float and int slots, flag rows, parameters."""
        return self._pos, self._start, self._target, self._fv, self._iv, self._flags, self._params

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

    def is_standing(self, agent: int) -> bool:
        """Whether the agent has no motion under way: it stays where it is until given a goal
        (nothing pushes a standing agent)."""
        return bool(self._iv[agent, I_PHASE] == IDLE)

    @property
    def alive(self) -> np.ndarray:
        """(N,) False for removed agents."""
        return self._iv[:, I_ALIVE] != 0

    def _agent(self, agent: int, alive: bool = False) -> int:
        if not 0 <= agent < self.n:
            raise ValueError(f"no agent {agent} (there are {self.n})")
        if alive and not self._iv[agent, I_ALIVE]:
            raise ValueError(f"agent {agent} was removed")
        return int(agent)

    def _airborne(self, i: int) -> bool:
        """On a jump or drop edge: rising, gliding over the gap or box edge, or falling."""
        return self._iv[i, I_PHASE] in (RISE, GLIDE, FALL)

    def set_goal(
        self,
        agent: int,
        target: np.ndarray,
        kind: int,
        speed: float,
        max_speed: float | None = None,
    ) -> None:
        """Cross the edge from the agent's node to `target` (3,) at `speed` m/s (capped by its
        max speed, first set to `max_speed` if given); the edge `kind` (EdgeKind) chooses
        walking, jumping or dropping."""
        i = self._agent(agent, alive=True)
        cap = -1.0  # keep the agent's cap
        if max_speed is not None:
            if not max_speed >= 0.0:
                raise ValueError(f"max speed must be >= 0 m/s, got {max_speed!r}")
            cap = float(max_speed)
        goal = np.asarray(target, dtype=np.float64).reshape(-1)
        if len(goal) != 3:
            raise ValueError(f"target must be a finite (3,) position, got {target!r}")
        x, y, z = goal.tolist()
        if not (math.isfinite(x) and math.isfinite(y) and math.isfinite(z)):
            raise ValueError(f"target must be a finite (3,) position, got {target!r}")
        if not (math.isfinite(speed) and speed >= 0.0):
            raise ValueError(f"speed must be a finite number >= 0 m/s, got {speed!r}")
        if kind not in _EDGE_KINDS:
            names = ", ".join(k.name for k in EdgeKind)
            raise ValueError(f"{kind!r} is not an edge kind ({names})")
        started = begin_edge(
            i, x, y, z, np.uint8(kind), float(speed), cap, self.jump_speed, self.gravity,
            self._pos, self._target, self._fv, self._iv,
        )  # fmt: skip
        if not started:
            raise ValueError(f"agent {i} is in the air; give it a goal once it lands")

    def clear_goal(self, agent: int) -> None:
        """Stand still. An agent on a jump or drop edge cannot stop in the air: it lands at its
        target first, which is reported as an arrival."""
        i = self._agent(agent)
        if not self._airborne(i):
            self._iv[i, I_PHASE] = IDLE
            self._fv[i, F_CARRY] = 0.0

    def remove(self, agent: int) -> None:
        """A dead agent stops where it is, for good, and no longer blocks anyone."""
        i = self._agent(agent)
        self._iv[i, I_ALIVE] = 0
        self._iv[i, I_PHASE] = IDLE
        self._fv[i, [F_VZ, F_CARRY]] = 0.0

    def place(self, agent: int, position: np.ndarray) -> None:
        """Put an alive agent on `position` (3,) with no goal: a relocation by the caller."""
        i = self._agent(agent, alive=True)
        where = np.asarray(position, dtype=np.float64).reshape(-1)
        if where.shape != (3,) or not np.all(np.isfinite(where)):
            raise ValueError(f"position must be a finite (3,) point, got {position!r}")
        self._pos[i] = where
        self._start[i] = where
        self._iv[i, [I_PHASE, I_RECOVER, I_BLOCKED, I_ATTEMPTS]] = 0
        self._fv[i, [F_VZ, F_CARRY]] = 0.0

    def set_max_speed(self, agent: int, speed: float) -> None:
        """Change an agent's speed cap; it applies from its next goal."""
        i = self._agent(agent)
        if not speed >= 0.0:
            raise ValueError(f"max speed must be >= 0 m/s, got {speed!r}")
        self._fv[i, F_MAX_SPEED] = float(speed)

    def _new_flags(self) -> tuple[np.ndarray, MoveStep]:
        """The flags and `MoveStep` of the next call, cleared: the mover's own, reused by every
        `step` and `glide` (so a caller copies what it keeps past the next call)."""
        flags, out = self._flags, self._out
        flags.fill(False)
        out.happened = ARRIVAL | STUCK | TELEPORT
        return flags, out

    def step(self) -> MoveStep:
        """Advance every agent by one tick. The `MoveStep` is the mover's own: the next `step`
        or `glide` overwrites it (copy what you keep)."""
        return self.glide(1)[1]

    def glide(self, max_ticks: int) -> tuple[int, MoveStep]:
        """Advance up to `max_ticks` ticks in one call, stopping after the first tick in which an
        agent arrives, is declared stuck or is teleported; returns the ticks advanced and that
        last tick's `MoveStep` (`moved`: over all of them). Each tick is computed exactly as
        `step` computes it; each mover computes it."""
        raise NotImplementedError


def read_only(array: np.ndarray) -> np.ndarray:
    view = array.view()
    view.flags.writeable = False
    return view
