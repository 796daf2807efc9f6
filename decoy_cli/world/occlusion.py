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
precision (`benchmarks/occlusion_agreement.py` measures how often).
"""

from __future__ import annotations

import numpy as np

from decoy_cli.world.world import World


class OcclusionScene:
    """The world's triangles in an Embree scene; `clear(starts, ends)` tests segments."""

    def __init__(self, world: World) -> None:
        from embreex import rtcore_scene
        from embreex.mesh_construction import TriangleMesh

        low, high = world.bounds
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
        segment = ends - starts
        length = np.sqrt(np.einsum("ij,ij->i", segment, segment))
        direction = np.where(length[:, None] > 0.0, segment, [0.0, 0.0, 1.0])
        direction /= np.where(length > 0.0, length, 1.0)[:, None]
        occluded = self._scene.run(
            np.ascontiguousarray(starts - self.origin, dtype=np.float32),
            np.ascontiguousarray(direction, dtype=np.float32),
            dists=np.ascontiguousarray(length, dtype=np.float32),
            query="OCCLUDED",
        )
        return np.asarray(occluded) == -1
