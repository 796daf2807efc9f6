"""Throughput of the fidelity metrics on synthetic player-rounds of realistic length.

A player-round is an original and a simulated trajectory of 150-300 frames (the length of real
ESTA rounds at 2 Hz): the original a random walk at running speed, the simulation the original
plus a drifting error, with an early death in some rounds of either. `trajectory_metrics`
computes all ten metrics of docs/metrics.md (both protocols) on each pair.
"""

from __future__ import annotations

import time

import numpy as np

from decoy_cli.bench.records import MetricsResult
from decoy_cli.metrics import trajectory_metrics

RUN_SPEED_M_PER_FRAME = 2.4
"""About 250 u/s at 2 Hz frames."""

PlayerRoundArrays = tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]
"""(original (F, 3), original alive (F,), simulated (F, 3), simulated alive (F,))."""


def walk(rng: np.random.Generator, frames: int) -> np.ndarray:
    """A random walk in the x-y plane at running speed, with a little height variation."""
    heading = np.cumsum(rng.normal(scale=0.4, size=frames))
    step = RUN_SPEED_M_PER_FRAME * rng.uniform(0.3, 1.0, size=frames)
    xy = np.cumsum(np.c_[np.cos(heading) * step, np.sin(heading) * step], axis=0)
    z = np.cumsum(rng.normal(scale=0.05, size=frames))
    return np.c_[xy, z]


def player_rounds(rng: np.random.Generator, count: int) -> list[PlayerRoundArrays]:
    """`count` synthetic player-rounds of 150-300 frames (module doc)."""
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


def metric_throughput(pairs: int = 2000, seed: int = 0) -> MetricsResult:
    """Player-round pairs per second of `trajectory_metrics`, one thread, after a warm-up."""
    if pairs < 1:
        raise ValueError(f"need at least one player-round, not {pairs}")
    rounds = player_rounds(np.random.default_rng(seed), pairs)
    trajectory_metrics(*rounds[0])  # JIT compile or load from the cache
    started = time.perf_counter()
    cpu_started = time.process_time()
    evaluated = sum(trajectory_metrics(*r).reason is None for r in rounds)
    wall = time.perf_counter() - started
    cpu = time.process_time() - cpu_started
    return {
        "pairs": pairs,
        "evaluated": int(evaluated),
        "mean_frames": float(np.mean([r[0].shape[0] for r in rounds])),
        "wall_s": wall,
        "cpu_s": cpu,
        "pairs_per_s": pairs / wall,
        "ms_per_pair": wall / pairs * 1e3,
    }
