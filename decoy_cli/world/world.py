"""The `World`: a triangle soup in metres (x east, y north, z up) plus what is known about it.

Every world the project uses, the built-in one made from the de_dust2 nav mesh or a user's own
mesh file, ends up as this one type; the waypoint builder, line of sight and the simulator only
ever see triangles.
"""

from __future__ import annotations

import hashlib
from dataclasses import dataclass, field

import numpy as np

from decoy_cli.errors import WorldError


@dataclass
class World:
    """Triangles (T, 3, 3) in metres, and a name and description of where they came from."""

    triangles: np.ndarray
    name: str
    source: str
    meta: dict[str, object] = field(default_factory=dict)

    def __post_init__(self) -> None:
        tri = np.asarray(self.triangles, dtype=np.float64)
        if tri.ndim != 3 or tri.shape[1:] != (3, 3):
            raise WorldError(f"{self.source}: triangles must have shape (T, 3, 3), got {tri.shape}")
        if len(tri) == 0:
            raise WorldError(f"{self.source}: the mesh has no triangles")
        if not np.all(np.isfinite(tri)):
            raise WorldError(f"{self.source}: the mesh holds NaN or infinite coordinates")
        self.triangles = tri

    @property
    def num_triangles(self) -> int:
        return len(self.triangles)

    @property
    def bounds(self) -> tuple[np.ndarray, np.ndarray]:
        """Minimum and maximum corner of the axis-aligned bounding box, metres."""
        pts = self.triangles.reshape(-1, 3)
        return pts.min(axis=0), pts.max(axis=0)

    def fingerprint(self) -> str:
        """SHA-256 of the triangle coordinates (float32): identifies the geometry in graph files."""
        return hashlib.sha256(self.triangles.astype("<f4").tobytes()).hexdigest()

    def vertices_and_indices(self) -> tuple[np.ndarray, np.ndarray]:
        """Shared-vertex form (unique vertices, (T, 3) indices), as physics engines want it."""
        flat = self.triangles.reshape(-1, 3)
        vertices, inverse = np.unique(flat, axis=0, return_inverse=True)
        return vertices, inverse.reshape(-1, 3).astype(np.int32)
