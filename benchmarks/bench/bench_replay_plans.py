"""Time `snap_round` on a de_dust2-sized synthetic graph and round.

The graph is an 80 × 75 lattice at 0.7 m (6,000 waypoints, about 47k edges, like the built
de_dust2 graph); the round has 5 players × 230 frames at 2 Hz (a full 115 s round) walking the
lattice at up to 3 edges per frame, with standing-still runs and 0.2 m of position noise.
Prints the median and range over repeats, each on a fresh graph (cold path cache).

    python benchmarks/bench/bench_replay_plans.py [--repeats 7]
"""

from __future__ import annotations

import argparse
import time
from types import SimpleNamespace

import numpy as np

from decoy_cli.replay import snap_round
from decoy_cli.waypoints.graph import DIRECTION_VECTORS, EdgeKind, WaypointGraph

SPACING = 0.7
NX, NY = 80, 75
PLAYERS, FRAMES = 5, 230


def lattice_graph() -> WaypointGraph:
    """An NX × NY 8-direction lattice, node (i, j) = i * NY + j at (0.7 i, 0.7 j, 0)."""
    i, j = np.meshgrid(np.arange(NX), np.arange(NY), indexing="ij")
    i, j = i.ravel(), j.ravel()
    positions = np.column_stack([i * SPACING, j * SPACING, np.zeros(len(i))])
    sources, targets, directions = [], [], []
    for d, (di, dj) in enumerate(DIRECTION_VECTORS):
        ok = (i + di >= 0) & (i + di < NX) & (j + dj >= 0) & (j + dj < NY)
        sources.append((i * NY + j)[ok])
        targets.append(((i + di) * NY + j + dj)[ok])
        directions.append(np.full(int(ok.sum()), d))
    source = np.concatenate(sources)
    return WaypointGraph(
        positions=positions,
        edge_source=source.astype(np.int32),
        edge_target=np.concatenate(targets).astype(np.int32),
        edge_kind=np.full(len(source), EdgeKind.WALK, dtype=np.uint8),
        edge_direction=np.concatenate(directions).astype(np.uint8),
        node_place=np.full(len(positions), -1, dtype=np.int16),
        place_names=[],
        regions={},
    )


def random_round(seed: int) -> SimpleNamespace:
    """Players walking the lattice: each frame stand still (40%) or move up to 3 cells."""
    rng = np.random.default_rng(seed)
    cells = np.zeros((PLAYERS, FRAMES, 2), dtype=np.int64)
    cells[:, 0] = rng.integers([5, 5], [NX - 5, NY - 5], size=(PLAYERS, 2))
    for f in range(1, FRAMES):
        step = rng.integers(-3, 4, size=(PLAYERS, 2)) * (rng.random((PLAYERS, 1)) > 0.4)
        cells[:, f] = np.clip(cells[:, f - 1] + step, 0, [NX - 1, NY - 1])
    xy = cells * SPACING + rng.normal(0.0, 0.2, size=cells.shape)
    position = np.concatenate([xy, np.zeros((PLAYERS, FRAMES, 1))], axis=2)
    alive = np.ones((PLAYERS, FRAMES), dtype=bool)
    alive[0, 150:] = False  # one death mid-round
    return SimpleNamespace(
        position=position,
        alive=alive,
        weapon=np.full((PLAYERS, FRAMES), "AK-47"),
        frame_seconds=np.arange(FRAMES) * 0.5,
        players=[SimpleNamespace(name=f"T-slot-{p}", side="T") for p in range(PLAYERS)],
    )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=7)
    args = parser.parse_args()
    round_ = random_round(0)
    times = []
    for _ in range(args.repeats):
        graph = lattice_graph()
        graph.adjacency  # noqa: B018 - build the sparse matrix outside the timing, as on load
        start = time.perf_counter()
        result = snap_round(round_, graph)
        times.append(time.perf_counter() - start)
    ms = np.array(times) * 1e3
    intervals = int(result.summary["intervals"].sum())
    print(
        f"graph {graph.num_nodes} waypoints, {graph.num_edges} edges; "
        f"round {PLAYERS} players x {FRAMES} frames, {intervals} intervals"
    )
    print(
        f"snap_round: median {np.median(ms):.1f} ms (range {ms.min():.1f}-{ms.max():.1f}) "
        f"over {args.repeats} repeats, cold path cache"
    )
    print(result.summary.to_string(index=False, float_format=lambda v: f"{v:.3f}"))


if __name__ == "__main__":
    main()
