"""Embree's occlusion query against pybullet's rays on the built-in world, eye to eye:
python benchmarks/studies/occlusion_agreement.py [PAIRS]

Draws PAIRS random segments between eye points (feet + eye height) over the waypoints, half
between any two waypoints and half between a waypoint and a point a few metres away (the
distances at which fights happen), tests them with both, and prints how many answers differ and
each one's time on this machine (both in this run, so the ratio is the comparable figure).
"""

from __future__ import annotations

import sys
import time

import numpy as np

from decoy_cli.bench.machine import machine_line
from decoy_cli.geometry import eye_point
from decoy_cli.waypoints.build import builtin_graph
from decoy_cli.world.navmesh import nav_world
from decoy_cli.world.physics import PhysicsWorld


def main() -> None:
    pairs = int(sys.argv[1]) if len(sys.argv) > 1 else 200_000
    graph = builtin_graph()
    rng = np.random.default_rng(0)
    eyes = eye_point(graph.positions)
    half = pairs // 2
    far_a, far_b = (eyes[rng.integers(len(eyes), size=half)] for _ in range(2))
    near_a = eyes[rng.integers(len(eyes), size=pairs - half)]
    near_b = near_a + rng.normal(0.0, 8.0, near_a.shape) * [1.0, 1.0, 0.2]
    starts, ends = np.vstack([far_a, near_a]), np.vstack([far_b, near_b])
    with PhysicsWorld(nav_world()) as physics:
        scene = physics.occlusion
        began = time.perf_counter()
        embree = scene.clear(starts, ends)
        embree_s = time.perf_counter() - began
        began = time.perf_counter()
        bullet = physics.line_of_sight(starts, ends)
        bullet_s = time.perf_counter() - began
    differ = np.flatnonzero(embree != bullet)
    print(machine_line())
    print(f"{pairs} segments, {bullet.mean():.1%} clear by pybullet")
    print(f"answers that differ: {len(differ)} ({len(differ) / pairs:.4%})")
    for k in differ[:10]:
        length = np.linalg.norm(ends[k] - starts[k])
        print(f"  {starts[k].round(3)} -> {ends[k].round(3)} ({length:.2f} m): "
              f"embree {'clear' if embree[k] else 'blocked'}, "
              f"pybullet {'clear' if bullet[k] else 'blocked'}")  # fmt: skip
    print(f"embree {embree_s:.3f} s, pybullet {bullet_s:.3f} s: {bullet_s / embree_s:.1f}x")


if __name__ == "__main__":
    main()
