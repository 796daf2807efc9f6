"""The shared plane geometry: wrapping, facing, bearings and the eye point."""

from __future__ import annotations

import numpy as np

from decoy_cli.csgo import EYE_HEIGHT_M
from decoy_cli.geometry import bearing, eye_point, facing_yaw, wrap_180, wrap_pi


def test_bearing_convention() -> None:
    # yaw 0 looks east: north is to the left (+), south to the right (-), west behind (-pi)
    dx, dy = np.array([0.0, 0.0, -5.0, 3.0]), np.array([5.0, -5.0, 0.0, 0.0])
    np.testing.assert_allclose(bearing(dx, dy, np.zeros(4)), [np.pi / 2, -np.pi / 2, -np.pi, 0])
    # a viewer looking 10 degrees north of east, the point due south of him: -100 degrees
    np.testing.assert_allclose(bearing(0.0, -5.0, 10.0), np.radians(-100.0))


def test_bearing_wraps_into_minus_pi_to_pi() -> None:
    yaws = np.array([350.0, 10.0, 180.0, -170.0, 720.0])
    to = np.radians([10, 350, 170, 170, 0])
    seen = bearing(np.cos(to), np.sin(to), yaws)
    np.testing.assert_allclose(np.degrees(seen), [20, -20, -10, -20, 0], atol=1e-9)
    assert np.all((seen >= -np.pi) & (seen < np.pi))


def test_wraps_are_half_open() -> None:
    np.testing.assert_allclose(wrap_pi(np.array([np.pi, -np.pi, 3 * np.pi])), [-np.pi] * 3)
    np.testing.assert_allclose(wrap_180(np.array([180.0, -180.0, 190.0, -190.0])),
                               [-180.0, -180.0, -170.0, 170.0])  # fmt: skip


def test_facing_yaw_looks_at_the_point() -> None:
    np.testing.assert_allclose(facing_yaw(np.array([1.0, 0.0, -1.0]), np.array([0.0, 2.0, 0.0])),
                               [0.0, 90.0, 180.0])  # fmt: skip
    np.testing.assert_allclose(bearing(3.0, -4.0, facing_yaw(3.0, -4.0)), 0.0, atol=1e-12)


def test_the_eye_stands_above_the_feet() -> None:
    feet = np.array([[[1.0, 2.0, 3.0]], [[np.nan, 0.0, 0.0]]])
    eyes = eye_point(feet)
    assert eyes.shape == feet.shape
    np.testing.assert_allclose(eyes[0, 0], [1.0, 2.0, 3.0 + EYE_HEIGHT_M])
    np.testing.assert_allclose(eye_point(feet[0], 1.5)[0], [1.0, 2.0, 4.5])
