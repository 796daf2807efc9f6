"""A `World` loaded headless into pybullet: batched ray tests and capsule overlap tests.

pybullet is the physics engine of the whole project; this module owns the pitfalls met with it:

* The world body's collision group and mask are set explicitly (its default group is not 1, and
  agents fall through); rays have group 1, so the world's mask includes bit 1, or every ray
  silently misses and everything looks visible.
* `rayTestBatch` refuses more than 16,384 rays per call (4,096 on macOS), and given exactly
  16,384 it silently returns only 16,383 results (pybullet 3.2.7): the last ray reads as a
  miss. Batches are split into 4,095 rays (no measurable speed difference) and the result
  count is checked.
* The vertex-array mesh API fails somewhere between 159k and 635k triangles; larger worlds are
  written to a temporary OBJ and loaded by file name.
"""

from __future__ import annotations

import ctypes
import os
import sys
import tempfile
from types import ModuleType
from typing import Self

import numpy as np

from decoy_cli.world.occlusion import OcclusionScene
from decoy_cli.world.world import World

WORLD_GROUP = 1
AGENT_GROUP = 2
FEET_LIFT_M = 0.1
"""How far above a player's feet the ray down to its floor starts, so the floor the player
stands on is found."""
FLOOR_DEPTH_M = 4.0
"""How far below the feet the floor is looked for: deeper than any fall in the data between two
frames; below that, the floor is unknown."""
_RAY_BATCH = 4095
_THREADED_RAYS = 512
_MAX_VERTEX_ARRAY_TRIANGLES = 150_000


def load_pybullet():
    """Import pybullet without its "pybullet build time" banner on the terminal.

    The banner is a C-level print at import (to stderr, or stdout on some builds), so both file
    descriptors point to /dev/null while pybullet is imported, and the C library's buffers are
    flushed there before they are restored. A failed import still raises as usual.
    """
    if "pybullet" in sys.modules:
        return sys.modules["pybullet"]
    sys.stdout.flush()
    sys.stderr.flush()
    saved = {fd: os.dup(fd) for fd in (1, 2)}
    try:
        with open(os.devnull, "w") as devnull:
            for fd in saved:
                os.dup2(devnull.fileno(), fd)
            import pybullet

            ctypes.CDLL(None).fflush(None)
    finally:
        for fd, copy in saved.items():
            os.dup2(copy, fd)
            os.close(copy)
    return pybullet


class PhysicsWorld:
    """A pybullet DIRECT client holding one static world mesh; use as a context manager."""

    def __init__(self, world: World) -> None:
        pybullet = load_pybullet()
        self.world = world
        self._p = pybullet
        self.client: int | None = pybullet.connect(pybullet.DIRECT)
        self.body = self._load(world)
        pybullet.setCollisionFilterGroupMask(
            self.body, -1, WORLD_GROUP, WORLD_GROUP | AGENT_GROUP, physicsClientId=self.client
        )
        self._capsules: list[int] = []
        self._capsule_shape: tuple[float, float] | None = None
        self._occlusion: OcclusionScene | None = None
        self._lendable: dict[tuple[float, float, int, int], list[int]] = {}

    def _load(self, world: World) -> int:
        p = self._p
        if world.num_triangles <= _MAX_VERTEX_ARRAY_TRIANGLES:
            vertices, indices = world.vertices_and_indices()
            shape = p.createCollisionShape(
                p.GEOM_MESH,
                vertices=vertices.tolist(),
                indices=indices.ravel().tolist(),
                flags=p.GEOM_FORCE_CONCAVE_TRIMESH,
                physicsClientId=self.client,
            )
        else:
            with tempfile.TemporaryDirectory() as folder:
                path = os.path.join(folder, "world.obj")
                _write_plain_obj(world, path)
                shape = p.createCollisionShape(
                    p.GEOM_MESH,
                    fileName=path,
                    flags=p.GEOM_FORCE_CONCAVE_TRIMESH,
                    physicsClientId=self.client,
                )
        return p.createMultiBody(
            baseMass=0, baseCollisionShapeIndex=shape, physicsClientId=self.client
        )

    @property
    def occlusion(self) -> OcclusionScene:
        """The world in an Embree scene for fast segment occlusion tests (built on first use,
        kept for the client's life): the simulator's line of sight."""
        if self._occlusion is None:
            self._occlusion = OcclusionScene(self.world)
        return self._occlusion

    @property
    def pybullet(self) -> ModuleType:
        """The pybullet module this client belongs to, for code that adds its own bodies (the
        movers' and line of sight's capsules)."""
        return self._p

    def lend_capsules(
        self, count: int, radius: float, height: float, group: int, mask: int
    ) -> list[int]:
        """`count` static upright capsule bodies of this shape in collision `group` against
        `mask`, taken from those given back (`take_back`) before new ones are made: making a
        body costs far more than moving one, and a simulator makes its bodies every round. Where
        they stand is the borrower's to set."""
        p = self._p
        key = (float(radius), float(height), int(group), int(mask))
        spare = self._lendable.setdefault(key, [])
        lent, spare[:] = spare[:count], spare[count:]
        if len(lent) < count:
            shape = p.createCollisionShape(
                p.GEOM_CAPSULE,
                radius=radius,
                height=max(height - 2 * radius, 1e-6),
                physicsClientId=self.client,
            )
            for _ in range(count - len(lent)):
                body = p.createMultiBody(
                    baseMass=0, baseCollisionShapeIndex=shape, physicsClientId=self.client
                )
                p.setCollisionFilterGroupMask(body, -1, group, mask, physicsClientId=self.client)
                lent.append(body)
        return lent

    def take_back(
        self, bodies: list[int], radius: float, height: float, group: int, mask: int
    ) -> None:
        """Bodies lent by `lend_capsules` with this shape, for the next borrower."""
        key = (float(radius), float(height), int(group), int(mask))
        self._lendable.setdefault(key, []).extend(bodies)

    def close(self) -> None:
        if self.client is not None and self._p.isConnected(self.client):
            self._p.disconnect(self.client)
        self.client = None

    def __enter__(self) -> Self:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    # ---- rays -------------------------------------------------------------------------------

    def cast_rays(self, starts: np.ndarray, ends: np.ndarray, mask: int = WORLD_GROUP) -> list:
        """pybullet's raw ray results (one tuple per ray) for rays that hit the groups in `mask`.

        Batches are split under pybullet's limit and checked for completeness; a batch of more
        than `_THREADED_RAYS` rays lets Bullet use every core (faster for thousands of rays, no
        gain for a few dozen).
        """
        starts = np.asarray(starts, dtype=np.float64).reshape(-1, 3)
        ends = np.asarray(ends, dtype=np.float64).reshape(-1, 3)
        results: list = []
        for lo in range(0, len(starts), _RAY_BATCH):
            chunk = starts[lo : lo + _RAY_BATCH]
            hits = self._p.rayTestBatch(
                chunk.tolist(),
                ends[lo : lo + _RAY_BATCH].tolist(),
                numThreads=0 if len(chunk) > _THREADED_RAYS else 1,
                collisionFilterMask=mask,
                physicsClientId=self.client,
            )
            if len(hits) != len(chunk):
                raise RuntimeError(f"pybullet returned {len(hits)} ray results for a batch")
            results.extend(hits)
        return results

    def ray_test(self, starts: np.ndarray, ends: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Cast rays against the world: (hit fraction in [0, 1], inf for a miss; hit normal z).

        Only the world mesh is hit (agents are in another collision group).
        """
        hits = self.cast_rays(starts, ends, WORLD_GROUP)
        fraction = np.full(len(hits), np.inf)
        normal_z = np.zeros(len(hits))
        for k, hit in enumerate(hits):
            if hit[0] == self.body:
                fraction[k] = hit[2]
                normal_z[k] = hit[4][2]
        return fraction, normal_z

    def first_floor_below(self, points: np.ndarray, depth: float) -> tuple[np.ndarray, np.ndarray]:
        """Height of the first surface straight below each point within `depth` (NaN if none).

        Returns (floor z, surface normal z).
        """
        points = np.asarray(points, dtype=np.float64).reshape(-1, 3)
        ends = points.copy()
        ends[:, 2] -= depth
        fraction, normal_z = self.ray_test(points, ends)
        z = np.where(np.isfinite(fraction), points[:, 2] - fraction * depth, np.nan)
        return z, normal_z

    def floor_under_feet(self, positions: np.ndarray) -> np.ndarray:
        """Height of the floor each player position (metres, (..., 3)) stands on or above: the
        first surface below a ray start `FEET_LIFT_M` above the feet, looked for down to
        `FLOOR_DEPTH_M` (NaN there and where the position is not finite)."""
        positions = np.asarray(positions, dtype=np.float64)
        floor = np.full(positions.shape[:-1], np.nan)
        finite = np.isfinite(positions).all(axis=-1)
        lifted = positions[finite] + np.array([0.0, 0.0, FEET_LIFT_M])
        floor[finite] = self.first_floor_below(lifted, FLOOR_DEPTH_M)[0]
        return floor

    def line_of_sight(self, starts: np.ndarray, ends: np.ndarray) -> np.ndarray:
        """True where nothing of the world lies between the two points."""
        fraction, _ = self.ray_test(starts, ends)
        return ~np.isfinite(fraction)

    # ---- capsule overlap --------------------------------------------------------------------

    def capsules_blocked(
        self, centres: np.ndarray, radius: float, height: float, tolerance: float = 0.01
    ) -> np.ndarray:
        """True where an upright capsule at the centre would penetrate the world.

        `height` is the full height of the capsule including both caps. Many capsules are placed
        at once and checked in one collision pass; they never collide with each other.
        """
        p = self._p
        centres = np.asarray(centres, dtype=np.float64).reshape(-1, 3)
        self._ensure_capsules(radius, height)
        blocked = np.zeros(len(centres), dtype=bool)
        pool = len(self._capsules)
        index = {body: k for k, body in enumerate(self._capsules)}
        for lo in range(0, len(centres), pool):
            chunk = centres[lo : lo + pool]
            for k, body in enumerate(self._capsules[: len(chunk)]):
                p.resetBasePositionAndOrientation(
                    body, chunk[k].tolist(), [0, 0, 0, 1], physicsClientId=self.client
                )
            p.performCollisionDetection(physicsClientId=self.client)
            for contact in p.getContactPoints(bodyA=self.body, physicsClientId=self.client):
                if contact[8] < -tolerance:
                    hit = index.get(contact[2])
                    if hit is not None and hit < len(chunk):
                        blocked[lo + hit] = True
            self._park(len(chunk))
        return blocked

    def _park(self, count: int) -> None:
        """Move the first `count` capsules far apart and away, and run a collision pass there.

        Bullet keeps a contact manifold per overlapping pair and, after a body is teleported,
        refreshes its old points instead of finding the new deepest one: a capsule moved from
        one wall into another can report a graze instead of a deep penetration. Parking every
        capsule where it overlaps nothing ends all pairs and their manifolds between batches.
        """
        p = self._p
        for k, body in enumerate(self._capsules[:count]):
            p.resetBasePositionAndOrientation(
                body, [0.0, 0.0, 1e6 + 10 * k], [0, 0, 0, 1], physicsClientId=self.client
            )
        p.performCollisionDetection(physicsClientId=self.client)

    def _ensure_capsules(self, radius: float, height: float, pool: int = 1024) -> None:
        """`pool` capsules of this shape for the overlap tests, parked (`lend_capsules`)."""
        if self._capsule_shape == (radius, height):
            return
        if self._capsule_shape is not None:
            self.take_back(self._capsules, *self._capsule_shape, AGENT_GROUP, WORLD_GROUP)
        self._capsules = self.lend_capsules(pool, radius, height, AGENT_GROUP, WORLD_GROUP)
        self._capsule_shape = (radius, height)
        self._park(pool)


def _write_plain_obj(world: World, path: str) -> None:
    vertices, indices = world.vertices_and_indices()
    with open(path, "w") as f:
        f.writelines(f"v {x:.6f} {y:.6f} {z:.6f}\n" for x, y, z in vertices)
        f.writelines(f"f {a + 1} {b + 1} {c + 1}\n" for a, b, c in indices)
