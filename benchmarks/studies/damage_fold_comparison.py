"""Damage outcome models on the same leave-rounds-out folds of real damaging steps:
python benchmarks/studies/damage_fold_comparison.py [EVENTS...] [--paper CHECKPOINTS] [--seed N]

The rules-grounded model (its parts fitted per fold), the paper's DOG (imported from its
published checkpoints, trained on other matches) and the shipped DOG (its label says how many
of these rounds it was trained or validated on, from its metadata: flattered on those) are
scored as decoy_cli/damage/fold_comparison.py says: mean Wasserstein per (weapon, hit group)
cell with at least 5 real samples, pooled and per fold, and the hit-group total variation per
weapon with at least 30 samples.
"""

from __future__ import annotations

import argparse
import tempfile
from pathlib import Path

import numpy as np
from _damage_folds import CvaeTraining, compare_on_folds, training_overlap

from decoy_cli.damage import SHIPPED_MODELS
from decoy_cli.damage.model_folder import load_dog
from decoy_cli.esta import collect_match_files, read_match
from decoy_cli.modeling.paper_import import import_paper
from decoy_cli.modeling.samples import build_samples
from decoy_cli.modeling.train_options import DogLossWeights, TrainOptions

SHARED = Path(__file__).resolve().parents[2].parent / "shared" / "data"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("inputs", nargs="*", type=Path, default=[SHARED / "esta_dust2_events"])
    parser.add_argument("--paper", type=Path, default=SHARED / "decoy_checkpoints")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument(
        "--no-cvae", action="store_true", help="skip training the project's CVAE per fold"
    )
    args = parser.parse_args()
    files, _ = collect_match_files(args.inputs)
    rounds = [r for f in files for r in read_match(f).rounds]
    samples, _ = build_samples(files)
    print(f"{int(samples.hit.sum())} damaging samples of {len(rounds)} rounds, 5 folds by round")
    with tempfile.TemporaryDirectory() as scratch:
        seen = training_overlap(load_dog(SHIPPED_MODELS).metadata, samples)
        folders = {f"shipped DOG ({seen})": SHIPPED_MODELS}
        if args.paper.is_dir():
            import_paper(args.paper, Path(scratch) / "paper")
            folders = {"paper DOG (imported checkpoint)": Path(scratch) / "paper", **folders}
        cvae = None
        if not args.no_cvae:  # the shipped DOG's training (models/DOG_CARD.md)
            options = TrainOptions(epochs=1000, batch_size=32, learning_rate=1e-3, patience=100)
            spec = load_dog(SHIPPED_MODELS).spec
            cvae = CvaeTraining(options, DogLossWeights(kl=0.05), spec)
        results = compare_on_folds(rounds, samples, folders, seed=args.seed, cvae=cvae)
    width = max(len(r.name) for r in results)
    print(
        f"{'model':<{width}} {'mean W':>7} {'max W':>7} {'floor':>6} {'cells':>5} "
        f"{'per fold':>14}  hit-group TV"
    )
    for r in results:
        folds = np.array(r.fold_means)
        tv = ", ".join(f"{w} {v:.3f}" for w, v in r.group_tv.items())
        print(
            f"{r.name:<{width}} {r.mean_wasserstein_hp:7.2f} {r.max_wasserstein_hp:7.2f} "
            f"{r.mean_floor_hp:6.2f} {r.cells:5d} {folds.mean():6.2f} ± {folds.std(ddof=1):4.2f}  "
            f"{tv}"
        )
    print("floor: the mean Wasserstein a model would score were the real samples drawn from it")


if __name__ == "__main__":
    main()
