"""How stable and how costly the evaluation's bootstrap intervals are, on a finished run.

    python benchmarks/studies/interval_study.py decoy-out/evaluate

Reads the run's `players.csv` and `summary.json`; for the clock `mean_dist` mean of every side
prints the 95% interval with two seeds and how far apart their bounds are, as a share of the
interval's width (the target is at most 10%), then the time to compute every trajectory
interval (`decoy_cli.evaluate.tables`) against the run's wall time.
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import numpy as np
import pandas as pd

from decoy_cli.evaluate.intervals import trajectory_intervals
from decoy_cli.evaluate.tables import trajectory_table
from decoy_cli.metrics import METRIC_NAMES, summarize


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("run", type=Path, help="an evaluate output folder")
    args = parser.parse_args()
    players = pd.read_csv(args.run / "players.csv")
    wall = json.loads((args.run / "summary.json").read_text())["wall_seconds"]
    table = trajectory_table(summarize(players[["side", *METRIC_NAMES, "reason"]]))
    runs = {}
    for seed in (0, 1):
        started = time.perf_counter()
        runs[seed] = trajectory_intervals(table, players, seed)
        seconds = time.perf_counter() - started
    mean_dist = [r[r["metric"] == "mean_dist"].set_index("group") for r in runs.values()]
    for group in mean_dist[0].index:
        a, b = mean_dist[0].loc[group], mean_dist[1].loc[group]
        if np.isnan(a["mean_low"]):
            continue
        width = a["mean_high"] - a["mean_low"]
        apart = max(abs(a["mean_low"] - b["mean_low"]), abs(a["mean_high"] - b["mean_high"]))
        print(
            f"{group}: mean_dist mean {a['mean']:.4f}, seed 0 [{a['mean_low']:.4f}, "
            f"{a['mean_high']:.4f}], seed 1 [{b['mean_low']:.4f}, {b['mean_high']:.4f}]: "
            f"bounds {apart:.4f} apart, {100 * apart / width:.1f}% of the width"
        )
    print(
        f"all trajectory intervals: {seconds:.2f} s, {100 * seconds / wall:.1f}% of the run's "
        f"wall time ({wall:.1f} s, {len(players)} player-rounds)"
    )


if __name__ == "__main__":
    main()
