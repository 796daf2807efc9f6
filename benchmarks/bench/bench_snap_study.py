"""How long `decoy snap FOLDER` takes on the real T-side data, stage by stage.

On the 15 matches (385 rounds) of ../shared/data/esta_dust2_tside with the shipped de_dust2
graph: reading every file, snapping and planning every round (`study_round` without metrics),
and the fidelity metrics of the snapped-waypoint trajectories (both protocols, all ten metrics,
on the real player-rounds). Each stage runs `--repeats` times; the median and range are shown.

    python benchmarks/bench/bench_snap_study.py [--repeats 3]
"""

from __future__ import annotations

import argparse
import statistics
import sys
import time
from collections.abc import Callable
from pathlib import Path

import numpy as np

from decoy_cli.esta import iter_match_files, read_match
from decoy_cli.metrics import trajectory_metrics
from decoy_cli.replay.snapping import SnapStatus
from decoy_cli.replay.study import study_round
from decoy_cli.waypoints.build import builtin_graph

DATA = Path(__file__).resolve().parents[2].parent / "shared" / "data" / "esta_dust2_tside"


def _times(step: Callable[[], object], repeats: int) -> list[float]:
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        step()
        times.append(time.perf_counter() - start)
    return times


def _show(name: str, times: list[float], count: int, unit: str) -> None:
    median = statistics.median(times)
    print(
        f"{name:<34} {median:>8.2f} s  [{min(times):.2f} - {max(times):.2f}]  "
        f"{count / median:>9,.0f} {unit}/s"
    )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=3, help="runs per stage")
    args = parser.parse_args()
    if not DATA.is_dir():
        sys.exit(f"real ESTA data not found at {DATA} (../shared/data next to the repo)")
    graph = builtin_graph()
    files = iter_match_files(DATA)

    matches = []
    read = _times(lambda: matches.append([read_match(f) for f in files]), args.repeats)
    rounds = [r for match in matches[-1] for r in match.rounds]
    studies = []
    snap = _times(lambda: studies.append([study_round(r, graph) for r in rounds]), args.repeats)

    pairs = []
    for round_, study in zip(rounds, studies[-1], strict=True):
        for p, snapped in enumerate(study.plan.snaps):
            ok = snapped.status == SnapStatus.SNAPPED
            simulated = np.full(round_.position[p].shape, np.nan)
            simulated[ok] = graph.positions[snapped.node[ok]]
            alive = round_.alive[p] & np.isfinite(round_.position[p]).all(axis=1)
            pairs.append((round_.position[p], alive, simulated, ok))
    trajectory_metrics(*pairs[0])  # JIT warm-up
    metrics = _times(lambda: [trajectory_metrics(*pair) for pair in pairs], args.repeats)

    frames = sum(r.num_frames for r in rounds)
    print(
        f"{len(files)} files, {len(rounds)} rounds, {len(pairs)} player-rounds, "
        f"{frames:,} frames; graph {graph.num_nodes:,} waypoints; median of {args.repeats} runs"
    )
    _show("read_match (all files)", read, len(files), "files")
    _show("snap + plan + intervals (all)", snap, len(rounds), "rounds")
    _show("metrics of snapped trajectories", metrics, len(pairs), "player-rounds")


if __name__ == "__main__":
    main()
