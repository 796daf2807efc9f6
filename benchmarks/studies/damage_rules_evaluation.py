"""The rules-grounded damage outcome model on real hits, leave-rounds-out:
python benchmarks/studies/damage_rules_evaluation.py [EVENTS...] [--seed N]

Hit group drawn from a model learned on the other folds' rounds, damage by the game's rules
(decoy_cli/damage/rules_evaluation.py). Prints the mean Wasserstein distance per (weapon, hit
group) cell with at least 5 real hits (pooled and per fold), every cell, and the hit-group total
variation per weapon with at least 30 hits. Default input: ../shared/data/esta_dust2_events.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np
import pandas as pd
from _damage_rules import evaluate_rules

from decoy_cli.esta import collect_match_files, read_match

DEFAULT = Path(__file__).resolve().parents[2].parent / "shared" / "data" / "esta_dust2_events"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("inputs", nargs="*", type=Path, default=[DEFAULT])
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args()
    files, _ = collect_match_files(args.inputs)
    rounds = [r for f in files for r in read_match(f).rounds]
    result = evaluate_rules(rounds, seed=args.seed)
    folds = np.array(result.fold_mean_wasserstein_hp)
    print(f"{result.hits} firearm hits in {result.rounds} rounds, 5 folds by round")
    print(
        f"mean Wasserstein per cell: {result.mean_wasserstein_hp:.2f} HP pooled over "
        f"{len(result.cells)} cells (largest {result.max_wasserstein_hp:.2f}); per fold "
        f"{folds.mean():.2f} ± {folds.std(ddof=1):.2f} HP ({', '.join(f'{v:.2f}' for v in folds)})"
    )
    floor = result.cells["floor_hp"]
    print(
        f"sampling floor (what the model would score were the real hits drawn from it): mean "
        f"{floor.mean():.2f} HP, largest cell {floor.max():.2f} HP"
    )
    with pd.option_context("display.width", 160):
        print(result.cells.round(3).to_string(index=False))
        print(result.group_tv.round(3).to_string(index=False))
    print("armour shares (kevlar, helmet) by buy type:", result.armour_shares)


if __name__ == "__main__":
    main()
