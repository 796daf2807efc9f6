"""Speed of the fidelity metrics: DTW / Fréchet kernels and full player-round evaluation.

Run: python benchmarks/bench/bench_metrics.py [--repeats N] [--pairs N]

Times, after JIT warm-up, the exact DTW and discrete Fréchet kernels on a 310 x 310 pair (the
longest ESTA rounds at 2 Hz) and on the paper protocol's 451 x 451 pair, `similaritymeasures` on
the same pair for comparison (a few repeats: it is slow), and the throughput of
`trajectory_metrics` (all ten metrics, both protocols) on synthetic player-rounds of realistic
length (150-300 frames, random walks at running speed with an early death in some rounds): the
same measurement as the metric section of `decoy bench` (`decoy_cli.bench.metrics`).
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

from decoy_cli.bench.metrics import metric_throughput, walk
from decoy_cli.metrics import dtw, frechet


def time_calls(call: Callable[[], object], repeats: int) -> list[float]:
    """Wall time in seconds of each of `repeats` calls."""
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        call()
        times.append(time.perf_counter() - start)
    return times


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

    result = metric_throughput(args.pairs, seed=1)
    print(
        f"trajectory_metrics (10 metrics, both protocols): {result['pairs']} player-rounds "
        f"(mean {result['mean_frames']:.0f} frames, {result['evaluated']} evaluated) in "
        f"{result['wall_s']:.3f} s = {result['pairs_per_s']:.0f} player-rounds/s "
        f"({result['ms_per_pair']:.3f} ms each), 1 thread"
    )


if __name__ == "__main__":
    main()
