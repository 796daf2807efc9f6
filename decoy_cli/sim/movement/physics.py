"""`PhysicsMover`: capsule agents in pybullet that block each other, with stuck recovery."""

from __future__ import annotations

import numpy as np

from decoy_cli.csgo import (
    AGENT_FLOAT_M,
    AGENT_GRAZE_M,
    AGENT_RADIUS_M,
    PLAYER_HEIGHT_M,
    TICK_RATE,
)
from decoy_cli.sim.movement.base import MoverBase
from decoy_cli.sim.movement.collision import physics_commit, physics_glide
from decoy_cli.sim.movement.interface import ARRIVAL, STUCK, TELEPORT, MoveStep
from decoy_cli.sim.movement.layout import (
    I_WAIT,
    P_ARRIVE_XY,
    P_ARRIVE_Z,
    P_CAP_LEN,
    P_MAX_SIDESTEPS,
    P_OCCUPIED_TOL,
    P_SIDESTEP_SPEED,
    P_SIDESTEP_TICKS,
    P_STUCK_TICKS,
    P_TWO_R,
    R_ARRIVED,
    R_MOVED,
    R_MOVING,
    R_STUCK,
    R_TELEPORTED,
    S_MODIFIED,
    SCRATCH_FLOAT_SLOTS,
    SCRATCH_INT_SLOTS,
)
from decoy_cli.world.physics import AGENT_GROUP, WORLD_GROUP, PhysicsWorld

ARRIVE_XY_M = 0.05
"""A held-back physics agent this close to its node horizontally has arrived..."""
ARRIVE_Z_M = 0.3
"""...if its feet are also this close vertically (3-D: a cell may hold two floors)."""
OCCUPIED_TOL_M = 0.1
"""A held-back agent touching another that stands on its goal has arrived if it is within this
distance of as close as the other lets it get."""


class PhysicsMover(MoverBase):
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
        radius: float = AGENT_RADIUS_M,
        height: float = PLAYER_HEIGHT_M,
        float_height: float = AGENT_FLOAT_M,
        graze: float = AGENT_GRAZE_M,
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
        p = physics.pybullet
        self._shape = p.createCollisionShape(
            p.GEOM_CAPSULE,
            radius=self.radius,
            height=self.capsule_length - 2 * self.radius,
            physicsClientId=physics.client,
        )
        self._bodies: list[int] = []
        super().__init__(tick_rate)
        prm = self._params
        prm[P_TWO_R], prm[P_CAP_LEN], prm[P_ARRIVE_XY], prm[P_ARRIVE_Z] = (
            2.0 * self.radius,
            self.capsule_length,
            ARRIVE_XY_M,
            ARRIVE_Z_M,
        )
        prm[P_SIDESTEP_SPEED] = 2.0 * self.radius / (self.sidestep_ticks * self.dt)
        prm[P_OCCUPIED_TOL] = OCCUPIED_TOL_M
        prm[P_STUCK_TICKS], prm[P_MAX_SIDESTEPS], prm[P_SIDESTEP_TICKS] = (
            self.stuck_ticks,
            self.max_sidesteps,
            self.sidestep_ticks,
        )

    def reset(self, positions: np.ndarray, max_speed: np.ndarray | float | None = None) -> None:
        super().reset(positions, max_speed)
        n = self.n
        self._iv[:, I_WAIT] = self.wait_ticks * (1 + np.arange(n) % 2)
        self._prop = np.zeros((n, 3))
        self._res = np.zeros((n, 3))
        self._sf = np.zeros((n, SCRATCH_FLOAT_SLOTS))
        self._si = np.zeros((n, SCRATCH_INT_SLOTS), dtype=np.int64)
        self._need_world = np.zeros(n, dtype=np.int64)
        p, client = self.physics.pybullet, self.physics.client
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
        p, client = self.physics.pybullet, self.physics.client
        changed = self.alive & np.any(self._pos != self._synced, axis=1)
        centres = self._pos + self._lift
        for k in np.flatnonzero(changed).tolist():
            p.resetBasePositionAndOrientation(
                self._bodies[k], centres[k].tolist(), (0.0, 0.0, 0.0, 1.0), physicsClientId=client
            )
        self._synced[changed] = self._pos[changed]

    def _park(self, k: int) -> None:
        p, client = self.physics.pybullet, self.physics.client
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
        p, client = self.physics.pybullet, self.physics.client
        if client is not None:
            for body in self._bodies:
                p.removeBody(body, physicsClientId=client)
        self._bodies = []

    def glide(self, max_ticks: int) -> tuple[int, MoveStep]:
        """Up to `max_ticks` ticks (see the class docstring for one) in one compiled call; a tick
        whose moves need the world test ends the call after the test and the commit."""
        flags, out = self._new_flags()
        args = (self._pos, self._start, self._target, self._fv, self._iv, self._prop, self._res)
        ticks, count, out.happened = physics_glide(
            *args, self._sf, self._si, self._need_world, flags, self._params, max(1, max_ticks)
        )
        if count:
            self._world_check(self._need_world[:count].tolist())
            physics_commit(*args, self._sf, self._si, flags, self._params)
            flags[R_MOVED] |= flags[R_MOVING]
            out.happened = (
                ARRIVAL * bool(flags[R_ARRIVED].any())
                | STUCK * bool(flags[R_STUCK].any())
                | TELEPORT * bool(flags[R_TELEPORTED].any())
            )
        return int(ticks), out

    def _world_check(self, agents: list[int]) -> None:
        """Cancel the moves of these agents (off their verified edge) that enter the world."""
        p, client, world = self.physics.pybullet, self.physics.client, self.physics.body
        self.world_checks += len(agents)
        centres = (self._res[agents] + self._lift).tolist()
        graze = -self.graze
        for i, centre in zip(agents, centres, strict=True):
            # the capsule's shape at the centre, without moving its body (synced lazily)
            points = p.getClosestPoints(
                -1,
                world,
                0.0,
                collisionShapeA=self._shape,
                collisionShapePositionA=centre,
                physicsClientId=client,
            )
            if any(point[8] < graze for point in points):
                self._res[i] = self._pos[i]
                self._si[i, S_MODIFIED] = 1
