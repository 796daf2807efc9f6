"""Occlusion queries against the world mesh with Intel Embree: is a segment clear of triangles?

The simulator's line of sight asks one question many times per combat step (every alive enemy
pair, eye to eye) and needs no hit point or normal, only whether anything lies between two
points. Embree's occlusion query (through `embreex`, the bindings trimesh uses) answers exactly
that, with an early exit at the first triangle found, and is an order of magnitude faster than
pybullet's `rayTestBatch`, which computes the closest hit of every ray. pybullet stays the
engine for everything that needs contacts, hit fractions or normals (`PhysicsWorld`).

Embree works in single precision, so the scene is stored relative to the centre of the world's
bounding box: coordinates then stay within the map's half-size, where float32 resolves a few
micrometres. The two answers agree except for rays that graze a triangle edge within that
precision (`benchmarks/studies/occlusion_agreement.py` measures how often).
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from decoy_cli.compiled import njit_cached
from decoy_cli.errors import WorldError
from decoy_cli.world.meshfile import MAX_EXTENT_M, read_mesh
from decoy_cli.world.world import World

SIGHT_FLOOR_SHARE = 0.8
"""Share of a map's waypoints a sight mesh must have a floor under (from 0.5 m above the feet
to 1 m below) to be taken for that map's geometry: chosen, not measured; a mesh of the map in
its units has nearly every waypoint on its floors, one of another map or in other units few."""


class OcclusionScene:
    """The world's triangles in an Embree scene; `clear(starts, ends)` tests segments."""

    def __init__(self, world: World) -> None:
        from embreex import rtcore_scene
        from embreex.mesh_construction import TriangleMesh

        low, high = world.bounds
        self.source = world.source
        self.sha256 = str(world.meta.get("file_sha256", ""))
        self.origin = (low + high) / 2.0
        self._scene = rtcore_scene.EmbreeScene()
        TriangleMesh(self._scene, (world.triangles - self.origin).astype(np.float32))

    def clear(self, starts: np.ndarray, ends: np.ndarray) -> np.ndarray:
        """(K,) True where no triangle lies on the segment from each start to its end (K, 3).

        A segment of zero length is clear."""
        starts = np.asarray(starts, dtype=np.float64).reshape(-1, 3)
        ends = np.asarray(ends, dtype=np.float64).reshape(-1, 3)
        if starts.shape != ends.shape:
            raise ValueError(f"{len(starts)} segment starts but {len(ends)} ends")
        if len(starts) == 0:
            return np.zeros(0, dtype=bool)
        origins, directions, lengths = _rays(starts, ends, self.origin)
        occluded = self._scene.run(origins, directions, dists=lengths, query="OCCLUDED")
        return np.asarray(occluded) == -1


def read_sight_scene(path: Path, feet: np.ndarray, map_name: str) -> OcclusionScene:
    """A map's own geometry for line of sight, from an awpy-style `.tri`, an awpy 3 `.mesh` or
    an `.obj` in Hammer units, z up (`read_mesh`). Refused (`WorldError`) when it is larger
    than a map or when fewer than `SIGHT_FLOOR_SHARE` of the map's waypoints (`feet`, metres)
    have a floor of it under them, as a mesh of another map or in other units would not."""
    world = read_mesh(path)
    low, high = world.bounds
    width = float(np.max(high[:2] - low[:2]))
    if width > MAX_EXTENT_M:
        raise WorldError(f"{path}: the mesh is {width:.4g} m across, too large for a map")
    scene = OcclusionScene(world)
    up, down = np.array([0.0, 0.0, 0.5]), np.array([0.0, 0.0, 1.0])
    share = float(np.mean(~scene.clear(feet + up, feet - down))) if len(feet) else 0.0
    if share < SIGHT_FLOOR_SHARE:
        raise WorldError(
            f"{path}: a floor under {share:.0%} of {map_name}'s waypoints: a mesh of another "
            "map, or not in Hammer units with z up"
        )
    return scene


@njit_cached
def _rays(starts, ends, origin):
    """Embree's rays for the segments: float32 starts relative to `origin`, unit directions
    (straight up for a zero-length segment) and lengths. One compiled pass: on the few rays of
    a combat step, numpy's per-call overhead would cost more than Embree's query itself."""
    k = starts.shape[0]
    origins = np.empty((k, 3), np.float32)
    directions = np.empty((k, 3), np.float32)
    lengths = np.empty(k, np.float32)
    for i in range(k):
        dx, dy, dz = ends[i, 0] - starts[i, 0], ends[i, 1] - starts[i, 1], ends[i, 2] - starts[i, 2]
        length = math.sqrt(dx * dx + dy * dy + dz * dz)
        if length > 0.0:
            dx, dy, dz = dx / length, dy / length, dz / length
        else:
            dx, dy, dz = 0.0, 0.0, 1.0
        for j in range(3):
            origins[i, j] = starts[i, j] - origin[j]
        directions[i, 0], directions[i, 1], directions[i, 2] = dx, dy, dz
        lengths[i] = length
    return origins, directions, lengths
