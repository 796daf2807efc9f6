"""Line of sight: which alive enemies see each other, eye to eye (`LineOfSight.visible_pairs`).

The combat step's first part (`decoy_cli.sim.combat`, which re-exports these names), split from
it because it is pybullet ray geometry, while the rest of the step is numpy over the visible
pairs.

Line of sight, and what Bullet does with rays that start inside a body (measured, pybullet
3.2.7): a ray leaving a capsule from inside misses it when it points up or sideways, but reports
a hit at fraction 0 on that capsule when it points down. So the eye-to-eye test is split in two
ray batches:

* world segments, eye to eye, tested against the world mesh only, with Embree's occlusion
  query (`PhysicsWorld.occlusion`, much faster than pybullet's closest-hit rays);
* for the pairs the world lets through, body rays that see only this module's capsules. They
  start 1 mm past the point where the segment leaves the first agent's own capsule (computed
  exactly: the eye lies on the capsule's axis) and end at the second agent's eye, inside its
  capsule. The first capsule hit is then the target's (clear) or another agent's (blocked);
  nothing hit is clear.

The capsules live in collision group `LOS_GROUP` with mask `WORLD_GROUP` (a ray's group is 1, so
a body is ray-tested only if its mask holds bit 1). The world's mask (WORLD_GROUP | AGENT_GROUP)
excludes LOS_GROUP, so they collide with nothing: `PhysicsWorld.capsules_blocked` and the
mover's capsules (AGENT_GROUP) never see them, and the rays here never see the mover's capsules.
Capsules of another `LineOfSight` in the same pybullet client are in the same group and do block.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from decoy_cli.compiled import njit_cached
from decoy_cli.csgo import EYE_HEIGHT_M, PLAYER_HEIGHT_M, PLAYER_RADIUS_M
from decoy_cli.geometry import eye_point
from decoy_cli.sim.state import Agents
from decoy_cli.world.occlusion import OcclusionScene
from decoy_cli.world.physics import WORLD_GROUP, PhysicsWorld

LOS_GROUP = 4
"""Collision group of the line-of-sight capsules: hit by this module's rays, touching nothing."""

_START_PAST_OWN_CAPSULE_M = 1e-3
_PARK_Z = -1e6


@dataclass(frozen=True)
class VisiblePairs:
    """K ordered (attacker, victim) agent index pairs, sorted by attacker then victim."""

    attacker: np.ndarray  # (K,) int64
    victim: np.ndarray  # (K,) int64

    def __len__(self) -> int:
        return len(self.attacker)


class LineOfSight:
    """Eye-to-eye visibility of alive enemies, blocked by the world and by other agents' bodies.

    Holds `count` upright capsules (radius and full height in metres, standing on the feet) in
    the physics client, one per agent; eyes are `eye_height` above the feet, inside the capsule.
    `scene` tests the world part of a sight line against other geometry than the physics
    client's (a map's own geometry: `read_sight_scene`); None: the physics world's.
    """

    def __init__(
        self,
        physics: PhysicsWorld,
        count: int,
        radius: float = PLAYER_RADIUS_M,
        height: float = PLAYER_HEIGHT_M,
        eye_height: float = EYE_HEIGHT_M,
        *,
        scene: OcclusionScene | None = None,
    ) -> None:
        if count < 0:
            raise ValueError(f"cannot hold {count} agents")
        if not 0 < radius <= height / 2:
            raise ValueError(f"capsule radius {radius} m does not fit a height of {height} m")
        if not 0 < eye_height < height:
            raise ValueError(f"eye height {eye_height} m is not inside a {height} m body")
        self._p = physics.pybullet
        self.physics = physics
        self.scene = scene if scene is not None else physics.occlusion
        self.count = count
        self.radius = float(radius)
        self.height = float(height)
        self.eye_height = float(eye_height)
        p = self._p
        self.bodies: list[int] = physics.lend_capsules(
            count, self.radius, self.height, LOS_GROUP, WORLD_GROUP
        )
        for k, body in enumerate(self.bodies):
            p.resetBasePositionAndOrientation(
                body, _park_position(k), [0.0, 0.0, 0.0, 1.0], physicsClientId=physics.client
            )
        self._owner = {body: k for k, body in enumerate(self.bodies)}
        self._placed = np.full((count, 3), np.nan)  # feet each capsule stands on; NaN = parked
        self._pairs_key: tuple[bytes, bytes] | None = None  # `_enemy_pairs`' cache
        self._pairs = (np.zeros(0, np.int64), np.zeros(0, np.int64))

    def close(self) -> None:
        """Give the capsules back to the physics client for the next round (the client stays
        open); parked, they block nothing."""
        shape = (self.radius, self.height, LOS_GROUP, WORLD_GROUP)
        if self.physics.client is not None and self._p.isConnected(self.physics.client):
            for k, body in enumerate(self.bodies):
                self._p.resetBasePositionAndOrientation(
                    body, _park_position(k), [0.0, 0.0, 0.0, 1.0],
                    physicsClientId=self.physics.client,
                )  # fmt: skip
            self.physics.take_back(self.bodies, *shape)
        self.bodies = []
        self._owner = {}

    def visible_pairs(self, agents: Agents) -> VisiblePairs:
        """All ordered (attacker, victim) pairs of alive agents of opposite sides that see each
        other, eye to eye; both orders of a visible pair are returned (visibility is symmetric).

        Blocked by the world and by the capsule of any other alive agent (either side); dead
        agents neither see nor block. Agents whose bodies overlap see each other.
        """
        if agents.count != self.count:
            raise ValueError(f"line of sight holds {self.count} agents, got {agents.count}")
        if len(self.bodies) != self.count:
            raise ValueError("line of sight is closed")
        alive = np.asarray(agents.alive, dtype=bool)
        first, second = self._enemy_pairs(agents, alive)
        if len(first) == 0:
            return _no_pairs()
        feet = np.asarray(agents.position, dtype=np.float64)
        starts, ends, finite = _eye_segments(feet, first, second, self.eye_height)
        if not finite:
            raise ValueError("an alive agent has a NaN or infinite position")
        clear = self.scene.clear(starts, ends)
        if not clear.any():
            return _no_pairs()
        if np.count_nonzero(alive) > 2:
            eyes = eye_point(feet, self.eye_height)
            self._place(feet, alive)
            ray = np.flatnonzero(clear)
            clear[ray] = self._bodies_clear(eyes, first[ray], second[ray])
        attacker = np.concatenate([first[clear], second[clear]])
        victim = np.concatenate([second[clear], first[clear]])
        order = np.lexsort((victim, attacker))
        return VisiblePairs(attacker[order].astype(np.int64), victim[order].astype(np.int64))

    def _enemy_pairs(self, agents: Agents, alive: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Every (T, CT) pair of alive agents, T-major, as (lower index, higher index): the
        rays run from the lower to the higher. Kept while the sides and the living stay."""
        key = (agents.side.tobytes(), alive.tobytes())
        if key != self._pairs_key:
            t_side = np.flatnonzero(alive & (agents.side == "T"))
            ct_side = np.flatnonzero(alive & (agents.side == "CT"))
            one = np.repeat(t_side, len(ct_side))
            two = np.tile(ct_side, len(t_side))
            self._pairs = (np.minimum(one, two), np.maximum(one, two))
            self._pairs_key = key
        return self._pairs

    def _place(self, feet: np.ndarray, alive: np.ndarray) -> None:
        """Stand the capsules of alive agents on their feet and park the others (only moves
        capsules whose place changed)."""
        p = self._p
        client = self.physics.client
        wanted = np.where(alive[:, None], feet, np.nan)
        same = np.all((wanted == self._placed) | (np.isnan(wanted) & np.isnan(self._placed)), 1)
        for k in np.flatnonzero(~same):
            if alive[k]:
                centre = [feet[k, 0], feet[k, 1], feet[k, 2] + self.height / 2]
            else:
                centre = _park_position(int(k))
            p.resetBasePositionAndOrientation(
                self.bodies[k], centre, [0.0, 0.0, 0.0, 1.0], physicsClientId=client
            )
        self._placed = wanted

    def _bodies_clear(self, eyes: np.ndarray, first: np.ndarray, second: np.ndarray) -> np.ndarray:
        """True where no capsule but the two agents' own lies between their eyes."""
        segment = eyes[second] - eyes[first]
        length = np.linalg.norm(segment, axis=1)
        t = _capsule_exit(segment, self.eye_height, self.radius, self.height)
        t = t + _START_PAST_OWN_CAPSULE_M / np.where(length > 0, length, 1.0)
        clear = np.ones(len(first), dtype=bool)
        cast = np.flatnonzero((t < 1.0) & (length > 0))  # else the eyes share one body: clear
        starts = eyes[first[cast]] + t[cast, None] * segment[cast]
        ends = eyes[second[cast]]
        hits = self.physics.cast_rays(starts, ends, LOS_GROUP)
        hit = np.fromiter((self._owner.get(h[0], -2) if h[0] >= 0 else -1 for h in hits), int)
        clear[cast] = (hit == -1) | (hit == second[cast])
        return clear


@njit_cached
def _eye_segments(feet, first, second, eye):
    """The segments (K, 3) from the eyes of `first` to those of `second`, `eye` above their
    feet, and whether all of them are finite. Compiled: a combat step has a few dozen pairs, on
    which numpy's per-call overhead costs more than the arithmetic."""
    k = first.shape[0]
    starts = np.empty((k, 3))
    ends = np.empty((k, 3))
    finite = True
    for i in range(k):
        for axis in range(3):
            lift = eye if axis == 2 else 0.0
            starts[i, axis] = feet[first[i], axis] + lift
            ends[i, axis] = feet[second[i], axis] + lift
            finite = finite and math.isfinite(starts[i, axis]) and math.isfinite(ends[i, axis])
    return starts, ends, finite


def _park_position(k: int) -> list[float]:
    """Where capsule k waits while its agent is dead: far below the map, apart from the others."""
    return [0.0, 0.0, _PARK_Z - 10.0 * k]


def _no_pairs() -> VisiblePairs:
    return VisiblePairs(np.zeros(0, np.int64), np.zeros(0, np.int64))


def _capsule_exit(segment: np.ndarray, eye: float, radius: float, height: float) -> np.ndarray:
    """(K,) parameter t along each segment (eye + t * segment) where it leaves the upright
    capsule its eye stands in; the eye lies on the axis, `eye` above the capsule's bottom.

    The capsule is the union of a cylinder and two spheres; a segment starting inside a convex
    union leaves it at the largest exit parameter of its parts. Zero-length segments give 0.
    """
    dz = segment[:, 2]
    horizontal = np.hypot(segment[:, 0], segment[:, 1])
    length2 = np.einsum("ij,ij->i", segment, segment)
    low, high = radius, height - radius  # axis ends (sphere centres) above the bottom
    exit_t = np.zeros(len(segment))
    with np.errstate(divide="ignore", invalid="ignore"):
        for centre in (low, high):
            b = (eye - centre) * dz
            c = (eye - centre) ** 2 - radius**2
            disc = b * b - length2 * c
            root = (-b + np.sqrt(np.maximum(disc, 0.0))) / length2
            exit_t = np.maximum(exit_t, np.where((disc >= 0) & (length2 > 0), root, 0.0))
        side = np.where(horizontal > 0, radius / horizontal, np.inf)
        enter_slab = np.where(dz > 0, (low - eye) / dz, (high - eye) / dz)
        leave_slab = np.where(dz > 0, (high - eye) / dz, (low - eye) / dz)
        flat = dz == 0
        in_slab = low <= eye <= high
        enter_slab = np.where(flat, -np.inf if in_slab else np.inf, enter_slab)
        leave_slab = np.where(flat, np.inf if in_slab else -np.inf, leave_slab)
        leave = np.minimum(side, leave_slab)
        cylinder = (leave >= np.maximum(enter_slab, 0.0)) & np.isfinite(leave)
        exit_t = np.maximum(exit_t, np.where(cylinder, leave, 0.0))
    return exit_t
