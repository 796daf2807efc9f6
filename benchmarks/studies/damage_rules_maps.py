"""The rules-grounded damage model on real damaging steps of every map with damage events,
fitted leave-matches-out: python benchmarks/studies/damage_rules_maps.py [EVENTS...] [--seed N]

Each match of a map with several matches is left out in turn, the rounds of a map with one
match are dealt into 5 folds (decoy_cli/modeling/split.leave_matches_out); each fold's steps are
drawn by rules fitted on all the other folds' rounds, of every map. Scored per map on the HP
lost per step by (weapon, distance band) cell with at least 10 real steps
(decoy_cli/modeling/hp_lost.py), with the sampling floor; beside it the shipped rules.json
(fitted on all of these rounds of de_dust2, so flattered there).
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np
from _damage_folds import rules_out_of_fold

from decoy_cli.damage import SHIPPED_MODELS
from decoy_cli.damage.rules_damage import RulesFile
from decoy_cli.esta import collect_match_files, read_match
from decoy_cli.modeling.hp_lost import (
    HpLostScores,
    band_labels,
    distance_u,
    draw_outcomes,
    drawn_hp_lost,
    score_by_map,
)
from decoy_cli.modeling.network_evaluation import DRAWS
from decoy_cli.modeling.sample_set import Samples
from decoy_cli.modeling.samples import build_samples
from decoy_cli.modeling.split import leave_matches_out

SHARED = Path(__file__).resolve().parents[2].parent / "shared" / "data"


def _line(name: str, where: str, s: HpLostScores) -> str:
    bias = 100 * (s.drawn_mean_hp / s.real_mean_hp - 1)
    return (
        f"{name:<28} {where:<11} {s.steps:6d} {s.real_mean_hp:6.1f} {s.drawn_mean_hp:6.1f} "
        f"{bias:+6.1f}% {s.mean_wasserstein_hp:7.2f} {s.max_wasserstein_hp:7.2f} "
        f"{s.mean_floor_hp:6.2f} {len(s.cells):5d}"
    )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    default = [SHARED / "esta_dust2_events", SHARED / "events_ancient"]
    parser.add_argument("inputs", nargs="*", type=Path, default=default)
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args()
    files, _ = collect_match_files(args.inputs)
    rounds = [r for f in files for r in read_match(f).rounds]
    samples, stats = build_samples(files)
    positives = samples.take(np.flatnonzero(samples.hit))
    print(f"{len(positives)} damaging steps of {len(rounds)} rounds; left out: "
          f"{dict(stats.excluded)}; HP lost only: {dict(stats.partial)}")  # fmt: skip
    fold = leave_matches_out(positives, np.random.default_rng(args.seed))
    fitted, _ = rules_out_of_fold(rounds, positives, fold, args.seed, DRAWS)
    shipped, _ = draw_outcomes(RulesFile.load(SHIPPED_MODELS), positives, args.seed, DRAWS)
    print(
        f"{'model':<28} {'map':<11} {'steps':>6} {'real':>6} {'drawn':>6} {'bias':>7} "
        f"{'mean W':>7} {'max W':>7} {'floor':>6} {'cells':>5}"
    )
    by_map = {}
    for name, drawn in (("rules, leave-matches-out", fitted), ("shipped rules.json", shipped)):
        by_map[name] = score_by_map(positives, drawn)
        for where, scores in by_map[name].items():
            print(_line(name, where, scores))
    print("HP lost per step; W: Wasserstein per (weapon, distance band) cell; floor: what the")
    print("model would score were the real steps drawn from it")
    _largest_cells(positives, fitted, by_map["rules, leave-matches-out"])


def _largest_cells(
    positives: Samples, drawn: np.ndarray, by_map: dict[str, HpLostScores], count: int = 3
) -> None:
    """Each map's `count` largest cells of `by_map` (the scores of `drawn`), with the mean HP
    lost real and drawn."""
    lost = drawn_hp_lost(drawn, positives.victim_hp)
    bands = band_labels(distance_u(positives))
    for where, scores in by_map.items():
        if where == "all":
            continue
        for cell in sorted(scores.cells, key=lambda c: -c["wasserstein_hp"])[:count]:
            rows = (positives.map_name == where) & (positives.attacker_weapon == cell["weapon"])
            rows &= bands == cell["part"]
            print(
                f"largest cell {where} {cell['weapon']} {cell['part']}: {cell['real']} steps, "
                f"mean HP lost real {positives.hp_lost[rows].mean():.1f}, drawn "
                f"{lost[:, rows].mean():.1f}, W {cell['wasserstein_hp']:.2f} "
                f"(floor {cell['floor_hp']:.2f})"
            )


if __name__ == "__main__":
    main()
