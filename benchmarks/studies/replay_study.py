"""Replay every round of a folder with combat off and compare with the DECOY paper's Table 2.

    python benchmarks/studies/replay_study.py ../shared/data/esta_dust2_tside --mover physics \
        --csv decoy-out/replay_study.csv

The bomb is off too, unless `--bomb` (then it follows the data). Prints the clock and paper
metrics aggregated by side (mean, std, median, p90), the paper's T-side values beside them,
lateness and stuck/recovery counts per round, the worst rounds, and the wall time. It runs the
rounds through `decoy evaluate`'s runner (one worker process by default, so rounds/s is per
core), with a throw-away cache; `decoy evaluate` adds the figures and the report.
"""

from __future__ import annotations

import argparse
import tempfile
from pathlib import Path

import numpy as np

from decoy_cli.esta import iter_match_files
from decoy_cli.evaluate.backends import LocalBackend
from decoy_cli.evaluate.runner import make_settings, run_evaluation
from decoy_cli.metrics import METRIC_NAMES, summarize

PAPER_T = {
    "paper_euclidean": 0.420,
    "paper_dtw": 0.873,
    "paper_rmse": 5.155,
    "paper_frechet_2d": 4.030,
}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("folder", type=Path)
    parser.add_argument("--mover", default="kinematic", choices=("physics", "kinematic"))
    parser.add_argument("--limit", type=int, default=0, help="only the first N files")
    parser.add_argument("--workers", type=int, default=1, help="worker processes (default 1)")
    parser.add_argument("--csv", type=Path, default=None)
    parser.add_argument(
        "--bomb", action="store_true", help="the bomb follows the data (default: off)"
    )
    args = parser.parse_args()
    files = iter_match_files(args.folder)
    if args.limit:
        files = files[: args.limit]
    settings = make_settings(
        map_name="de_dust2",
        combat=False,
        bomb=args.bomb,
        models="none",
        mover=args.mover,
        seed=0,
    )
    with tempfile.TemporaryDirectory() as out, LocalBackend(args.workers) as backend:
        evaluation = run_evaluation(files, settings, Path(out), backend)
    wall = evaluation.compute_seconds
    players = evaluation.accumulator.players()
    rounds = evaluation.accumulator.round_rows()
    n_rounds = len(rounds)
    print(
        f"{n_rounds} rounds, {len(players)} player-rounds, {len(evaluation.failures)} failures, "
        f"{wall:.1f} s ({n_rounds / wall:.2f} rounds/s on {args.workers} worker processes, "
        f"mover {args.mover}, combat off, bomb {'on' if args.bomb else 'off'})"
    )
    for failure in evaluation.failures:
        print(f"  failed: {failure.file}:{failure.round_num}: {failure.message}")
    summary = summarize(players[["side", *METRIC_NAMES, "reason"]])
    table = summary.table
    t = table[table["group"] == "T"].set_index("metric")
    print(
        f"\n{'metric':<18}{'mean':>8}{'std':>8}{'median':>8}{'p90':>8}"
        f"{'paper T':>9}{'better by':>11}"
    )
    for name in METRIC_NAMES:
        row = t.loc[name]
        paper = PAPER_T.get(name)
        better = "" if paper is None else f"{1 - row['mean'] / paper:>10.0%}"
        paper_s = "" if paper is None else f"{paper:>9.3f}"
        print(
            f"{name:<18}{row['mean']:>8.3f}{row['std']:>8.3f}{row['median']:>8.3f}{row['p90']:>8.3f}"
            f"{paper_s:>9}{better:>11}"
        )
    print(f"unevaluated: {summary.unevaluated.to_dict('records')}")
    late = players["late_share"].to_numpy(dtype=float)
    p95 = players["late_p95_s"].to_numpy(dtype=float)
    over = players["late_over_frame"].sum() / max(int(players["targets"].sum()), 1)
    print(
        f"\nlateness: share of targets late, mean over player-rounds {np.nanmean(late):.1%}; "
        f"p95 lateness median {np.nanmedian(p95):.2f} s, p90 {np.nanpercentile(p95, 90):.2f} s; "
        f"targets reached more than 0.5 s late: {over:.2%} of {int(players['targets'].sum()):,}"
    )
    causes = {
        "the lattice's zig-zag (the straight line was within the cap)": "late_zigzag",
        "a way round something (the straight line was within the cap)": "late_detour",
        "over the speed cap even straight": "late_speed",
        "a gap of the graph (relocated)": "late_gap",
        "within the cap: the replay's own delay": "late_replay",
    }
    total = max(int(players["late_over_frame"].sum()), 1)
    print(
        "why those targets are late (the interval that added most lateness in their stretch): "
        + "; ".join(f"{what} {players[c].sum() / total:.0%}" for what, c in causes.items())
    )
    print(
        f"stuck episodes per round: mean {rounds['stuck'].mean():.2f}, "
        f"max {rounds['stuck'].max()}; "
        f"recoveries (teleports) per round: mean {rounds['recoveries'].mean():.2f}, "
        f"max {rounds['recoveries'].max()}; relocations total {rounds['relocations'].sum()}"
    )
    per_round = players.groupby(["match", "round"])["mean_dist"].mean().sort_values(ascending=False)
    print("\nworst rounds by mean of mean_dist:")
    for (match, num), value in per_round.head(5).items():
        print(f"  {match}:{num}  mean_dist {value:.2f} m")
    if args.csv:
        args.csv.parent.mkdir(parents=True, exist_ok=True)
        players.to_csv(args.csv, index=False)
        print(f"rows written to {args.csv}")


if __name__ == "__main__":
    main()
