"""How often, and how on time, a replay plants the bomb where the data did (issue 12).

    python benchmarks/plant_study.py ../shared/data/esta_dust2_tside [--workers 2] [--csv X]

Replays every round with the bomb on and combat off and prints: the rounds whose data shows a
completed plant (`bombPlantTick`), how many of them the replay completes too, plants the replay
completes where the data has none, the plant time error (replay against data, seconds, median and
p95), and why the missed plants did not happen (the replay's `plant_abort` reasons).
"""

from __future__ import annotations

import argparse
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import numpy as np
import pandas as pd

from decoy_cli.csgo import TICK_RATE
from decoy_cli.esta import RoundFailure, collect_match_files, iter_rounds
from decoy_cli.replay.replayer import ReplayOptions, replay_round
from decoy_cli.waypoints.build import builtin_graph

COLUMNS = [
    "file",
    "round",
    "data_planted",
    "data_s",
    "replay_planted",
    "replay_s",
    "site",
    "aborts",
]


def study_file(file: Path) -> list[tuple]:
    graph = builtin_graph()
    rows = []
    for item in iter_rounds([file]):
        if isinstance(item, RoundFailure):
            continue
        planted = item.bomb_plant_tick is not None and item.clock is not None
        data_s = float(item.clock.seconds(item.bomb_plant_tick)) if planted else np.nan
        result = replay_round(item, graph, ReplayOptions(combat=False, bomb=True, play_out=False))
        plants = [e for e in result.events if e.kind == "plant"]
        aborts = ",".join(
            str(e.data.get("reason")) for e in result.events if e.kind == "plant_abort"
        )
        rows.append(
            (
                file.name,
                item.round_num,
                planted,
                data_s,
                bool(plants),
                plants[0].tick / TICK_RATE if plants else np.nan,
                plants[0].data.get("site", "") if plants else "",
                aborts,
            )
        )
    return rows


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("folder", type=Path)
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--csv", type=Path, help="Write one row per round here.")
    args = parser.parse_args()
    files, _ = collect_match_files([args.folder])
    rows: list[tuple] = []
    with ProcessPoolExecutor(args.workers) as pool:
        for part in pool.map(study_file, files):
            rows += part
    table = pd.DataFrame(rows, columns=COLUMNS)
    if args.csv:
        table.to_csv(args.csv, index=False)
    real = table[table["data_planted"]]
    print(f"{len(table)} rounds; the data completes a plant in {len(real)}")
    print(f"the replay completes {int(real['replay_planted'].sum())} of them")
    extra = int(table[~table["data_planted"]]["replay_planted"].sum())
    print(f"plants where the data has none: {extra}")
    error = (real["replay_s"] - real["data_s"]).abs().dropna()
    if len(error):
        print(f"plant time error: median {error.median():.3f} s, p95 {error.quantile(0.95):.3f} s")
    missed = real[~real["replay_planted"]]["aborts"].replace("", "never began")
    print("missed plants by abort reasons:", {k: int(v) for k, v in missed.value_counts().items()})


if __name__ == "__main__":
    main()
