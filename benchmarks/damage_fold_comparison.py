"""Damage outcome models on the same leave-rounds-out folds of real damaging steps:
python benchmarks/damage_fold_comparison.py [EVENTS...] [--paper CHECKPOINTS] [--seed N]

The rules-grounded model (its parts fitted per fold), the paper's DOG (imported from its
published checkpoints, trained on other matches) and the shipped DOG (trained on 60% of these
very rounds, so flattered here) are scored as decoy_cli/damage/fold_comparison.py says: mean
Wasserstein per (weapon, hit group) cell with at least 5 real samples, pooled and per fold, and
the hit-group total variation per weapon with at least 30 samples.
"""

from __future__ import annotations

import argparse
import tempfile
from pathlib import Path

import numpy as np

from decoy_cli.damage import SHIPPED_MODELS
from decoy_cli.damage.fold_comparison import compare_on_folds
from decoy_cli.damage.paper import import_paper
from decoy_cli.damage.samples import build_samples
from decoy_cli.esta import collect_match_files, read_match

SHARED = Path(__file__).resolve().parents[1].parent / "shared" / "data"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("inputs", nargs="*", type=Path, default=[SHARED / "esta_dust2_events"])
    parser.add_argument("--paper", type=Path, default=SHARED / "decoy_checkpoints")
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args()
    files, _ = collect_match_files(args.inputs)
    rounds = [r for f in files for r in read_match(f).rounds]
    samples, _ = build_samples(files)
    print(f"{int(samples.hit.sum())} damaging samples of {len(rounds)} rounds, 5 folds by round")
    with tempfile.TemporaryDirectory() as scratch:
        folders = {"shipped DOG (trained on 60% of these rounds)": SHIPPED_MODELS}
        if args.paper.is_dir():
            import_paper(args.paper, Path(scratch) / "paper")
            folders = {"paper DOG (imported checkpoint)": Path(scratch) / "paper", **folders}
        results = compare_on_folds(rounds, samples, folders, seed=args.seed)
    print(f"{'model':<46} {'mean W':>7} {'max W':>7} {'cells':>5} {'per fold':>14}  hit-group TV")
    for r in results:
        folds = np.array(r.fold_means)
        tv = ", ".join(f"{w} {v:.3f}" for w, v in r.group_tv.items())
        print(
            f"{r.name:<46} {r.mean_wasserstein_hp:7.2f} {r.max_wasserstein_hp:7.2f} {r.cells:5d} "
            f"{folds.mean():6.2f} ± {folds.std(ddof=1):4.2f}  {tv}"
        )


if __name__ == "__main__":
    main()
