"""The players' plane geometry, written once: wrapping angles, the yaw that faces a point, a
point's bearing from a view, and the eye point above the feet.

Yaws follow awpy's viewX: degrees, 0 = +x, counter-clockwise. A bearing is the direction to a
point minus the viewer's yaw, radians wrapped to [-pi, pi): 0 straight ahead, positive to the
left. The functions take the horizontal difference as its two components (`dx`, `dy`, the
target minus the viewer) and hand them to `np.arctan2` as they are given. Compiled kernels (the
movers' headings) compute theirs with `math.atan2` on scalars, which may differ from numpy's in
the last bit, so they keep their own.
"""

from __future__ import annotations

from typing import TypeVar

import numpy as np

from decoy_cli.csgo import EYE_HEIGHT_M

__all__ = ["Angles", "bearing", "eye_point", "facing_yaw", "wrap_180", "wrap_pi"]

Angles = TypeVar("Angles", np.ndarray, float)
"""Angles or coordinate differences: an array of them, or one (the answer is of the same kind)."""


def wrap_pi(angle: Angles) -> Angles:
    """Angles in radians wrapped to [-pi, pi) (the floored remainder)."""
    return (angle + np.pi) % (2 * np.pi) - np.pi


def wrap_180(angle: Angles) -> Angles:
    """Angles in degrees wrapped to [-180, 180) (the floored remainder)."""
    return (angle + 180.0) % 360.0 - 180.0


def facing_yaw(dx: Angles, dy: Angles) -> Angles:
    """The view yaw, degrees in (-180, 180], that looks along (dx, dy): toward a point that far
    away."""
    return np.degrees(np.arctan2(dy, dx))


def bearing(dx: Angles, dy: Angles, yaw: Angles) -> Angles:
    """The bearing, radians in [-pi, pi), of the point (dx, dy) away seen by a viewer whose yaw
    is `yaw` degrees (module docstring)."""
    return wrap_pi(np.arctan2(dy, dx) - np.radians(yaw))


def eye_point(feet: np.ndarray, eye_height: float = EYE_HEIGHT_M) -> np.ndarray:
    """(..., 3) the eyes of players standing on `feet` (..., 3): `eye_height` metres above."""
    return feet + np.array([0.0, 0.0, eye_height])
