"""How faithfully a replay's bomb follows real rounds: plants, defuses, sites, times.

    python benchmarks/studies/plant_study.py ../shared/data/esta_dust2_tside [--workers 2] [--csv X]

Runs the rounds through `decoy evaluate`'s runner with the bomb on and combat off (the data's
deaths scripted), so the bomb is the only thing that can differ from the data, and prints the
evaluation's bomb table (docs/metrics.md), the plant confusion, the rounds where the data and
the replay disagree about a plant, and the data's anomalies. `--csv` writes the round rows
(rounds.csv's columns) for a closer look.
"""

from __future__ import annotations

import argparse
import tempfile
from pathlib import Path

from decoy_cli.esta import iter_match_files
from decoy_cli.evaluate.backends import LocalBackend
from decoy_cli.evaluate.bomb_report import bomb_rows
from decoy_cli.evaluate.runner import make_settings, run_evaluation
from decoy_cli.evaluate.tables import build_tables


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("folder", type=Path)
    parser.add_argument("--workers", type=int, default=1, help="worker processes (default 1)")
    parser.add_argument("--mover", default="kinematic", choices=("physics", "kinematic"))
    parser.add_argument("--csv", type=Path, help="Write one row per round here.")
    args = parser.parse_args()
    settings = make_settings(
        map_name="de_dust2", combat=False, bomb=True, models="none", mover=args.mover, seed=0
    )
    files = iter_match_files(args.folder)
    with tempfile.TemporaryDirectory() as out, LocalBackend(args.workers) as backend:
        evaluation = run_evaluation(files, settings, Path(out), backend)
    tables = build_tables(evaluation.accumulator)
    rounds = tables.rounds
    if args.csv:
        rounds.to_csv(args.csv, index=False)
    bomb = tables.bomb
    assert bomb is not None  # the bomb is on
    print(
        f"{len(rounds)} rounds ({len(evaluation.failures)} failures), {bomb.n_rounds} with bomb "
        f"data; mover {args.mover}, combat off, bomb on"
    )
    for metric, value, interval, count, note in bomb_rows(bomb):
        print(f"  {metric:<32}{value:>8} {interval:<18} over {count} rounds {note}")
    print("plants, data (rows) against replay (columns):")
    print(bomb.plant_confusion.to_string())
    disagree = rounds[rounds["plant_data"].astype(bool) != rounds["plant_replay"].astype(bool)]
    for row in disagree.itertuples():
        print(
            f"  {row.match}:{row.round}: data {'planted' if row.plant_data else 'no plant'}, "
            f"replay {'planted' if row.plant_replay else 'no plant'}"
        )
    odd = rounds[rounds["bomb_anomalies"].fillna("") != ""]
    for row in odd.itertuples():
        print(f"  anomaly {row.match}:{row.round}: {row.bomb_anomalies}")


if __name__ == "__main__":
    main()
