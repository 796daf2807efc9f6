"""Speed of the fidelity metrics: DTW / Fréchet kernels and full player-round evaluation.

Run: python benchmarks/bench_metrics.py [--repeats N] [--pairs N]

Times, after JIT warm-up, the exact DTW and discrete Fréchet kernels on a 310 x 310 pair (the
longest ESTA rounds at 2 Hz) and on the paper protocol's 451 x 451 pair, `similaritymeasures` on
the same pair for comparison (a few repeats: it is slow), and the throughput of
`trajectory_metrics` (all ten metrics, both protocols) on synthetic player-rounds of realistic
length (150-300 frames, random walks at running speed with an early death in some rounds).
"""

from __future__ import annotations

import argparse
import os
import platform
import statistics
import time
from collections.abc import Callable

import numba
import numpy as np
import similaritymeasures

from decoy_cli.metrics import dtw, frechet, trajectory_metrics

RUN_SPEED_M_PER_FRAME = 2.4  # ~250 u/s at 2 Hz frames


def time_calls(call: Callable[[], object], repeats: int) -> list[float]:
    """Wall time in seconds of each of `repeats` calls."""
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        call()
        times.append(time.perf_counter() - start)
    return times


def walk(rng: np.random.Generator, frames: int) -> np.ndarray:
    """A random walk in the x-y plane at running speed, with a little height variation."""
    heading = np.cumsum(rng.normal(scale=0.4, size=frames))
    step = RUN_SPEED_M_PER_FRAME * rng.uniform(0.3, 1.0, size=frames)
    xy = np.cumsum(np.c_[np.cos(heading) * step, np.sin(heading) * step], axis=0)
    z = np.cumsum(rng.normal(scale=0.05, size=frames))
    return np.c_[xy, z]


def player_rounds(
    rng: np.random.Generator, count: int
) -> list[tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]]:
    """Synthetic (original, alive, simulated, alive) player-rounds of 150-300 frames."""
    rounds = []
    for _ in range(count):
        frames = int(rng.integers(150, 301))
        original = walk(rng, frames)
        simulated = original + np.cumsum(rng.normal(scale=0.3, size=(frames, 3)), axis=0)
        original_alive = np.ones(frames, dtype=bool)
        simulated_alive = np.ones(frames, dtype=bool)
        if rng.random() < 0.5:
            original_alive[int(rng.integers(frames // 3, frames)) :] = False
        if rng.random() < 0.5:
            simulated_alive[int(rng.integers(frames // 3, frames)) :] = False
        rounds.append((original, original_alive, simulated, simulated_alive))
    return rounds


def row(label: str, times: list[float]) -> str:
    ms = [t * 1e3 for t in times]
    return (
        f"{label:<44} {len(ms):>7} {statistics.median(ms):>10.4f} {min(ms):>10.4f} {max(ms):>10.4f}"
    )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=500, help="timed calls per kernel case")
    parser.add_argument("--pairs", type=int, default=2000, help="player-rounds for throughput")
    args = parser.parse_args()

    rng = np.random.default_rng(0)
    cases = {
        "310x310 3-D": (walk(rng, 310), walk(rng, 310)),
        "451x451 3-D": (walk(rng, 451), walk(rng, 451)),
    }
    print(
        f"python {platform.python_version()}, numpy {np.__version__}, numba {numba.__version__}, "
        f"{os.cpu_count()} CPUs, {platform.processor() or platform.machine()}"
    )
    print(f"{'case':<44} {'repeats':>7} {'median ms':>10} {'min ms':>10} {'max ms':>10}")
    for name, (a, b) in cases.items():
        for label, call in (
            (f"dtw {name}", lambda a=a, b=b: dtw(a, b)),
            (f"frechet {name}", lambda a=a, b=b: frechet(a, b)),
            (f"frechet {name[:7]} 2-D (x-y)", lambda a=a, b=b: frechet(a[:, :2], b[:, :2])),
        ):
            call()  # JIT compile or load from cache
            print(row(label, time_calls(call, args.repeats)))

    a, b = cases["310x310 3-D"]
    for label, call in (
        ("similaritymeasures.dtw 310x310 3-D", lambda: similaritymeasures.dtw(a, b)),
        (
            "similaritymeasures.frechet_dist 310x310 3-D",
            lambda: similaritymeasures.frechet_dist(a, b),
        ),
    ):
        print(row(label, time_calls(call, 3)))
    print(
        f"check: |dtw - oracle| = {abs(dtw(a, b)[0] - similaritymeasures.dtw(a, b)[0]):.3g}, "
        f"|frechet - oracle| = {abs(frechet(a, b) - similaritymeasures.frechet_dist(a, b)):.3g}"
    )

    rounds = player_rounds(rng, args.pairs)
    trajectory_metrics(*rounds[0])  # warm-up
    start = time.perf_counter()
    evaluated = sum(trajectory_metrics(*r).reason is None for r in rounds)
    elapsed = time.perf_counter() - start
    mean_frames = np.mean([r[0].shape[0] for r in rounds])
    print(
        f"trajectory_metrics (10 metrics, both protocols): {len(rounds)} player-rounds "
        f"(mean {mean_frames:.0f} frames, {evaluated} evaluated) in {elapsed:.3f} s = "
        f"{len(rounds) / elapsed:.0f} player-rounds/s ({elapsed / len(rounds) * 1e3:.3f} ms each), "
        "1 thread"
    )


if __name__ == "__main__":
    main()
