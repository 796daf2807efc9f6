"""How long real plants and defuses take, from the bomb events of real matches.

    python benchmarks/studies/bomb_timing_study.py ../shared/data/esta_dust2_events

For every `plant_begin` followed by the same player's `plant`, and every `defuse_start` followed
by the same player's `defuse`, prints the duration on the round's clock (ticks at `tickRate`):
the measurements behind the rules' plant and defuse constants (decoy_cli/sim/rules_config.py).
"""

from __future__ import annotations

import argparse
from itertools import pairwise
from pathlib import Path

import numpy as np

from decoy_cli.esta import RoundFailure, collect_match_files, iter_rounds

PAIRS = {"plant_begin": "plant", "defuse_start": "defuse"}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("folder", type=Path)
    args = parser.parse_args()
    files, _ = collect_match_files([args.folder])
    took: dict[str, list[float]] = {start: [] for start in PAIRS}
    for item in iter_rounds(files):
        if isinstance(item, RoundFailure) or not len(item.bomb_events):
            continue
        events = item.bomb_events.sort_values("tick", kind="stable")
        rows = list(zip(events["bombAction"], events["playerName"], events["seconds"], strict=True))
        for (action, player, start), (after, same, end) in pairwise(rows):
            if action in PAIRS and after == PAIRS[action] and player == same:
                took[action].append(float(end - start))
    for start, durations in took.items():
        d = np.array(durations)
        if len(d):
            print(
                f"{start} -> {PAIRS[start]}: {len(d)} times, {d.min():.3f}-{d.max():.3f} s "
                f"(median {np.median(d):.3f} s)"
            )
        else:
            print(f"{start} -> {PAIRS[start]}: none")


if __name__ == "__main__":
    main()
