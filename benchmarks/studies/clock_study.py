"""Which clock the real files' `seconds` run on, against the game's clock from the ticks.

    python benchmarks/studies/clock_study.py ../shared/data/esta_dust2_tside

For each match file: its `tickRate`, the rate its frames' `seconds` were written at (ticks per
written second), and the longest round without a plant measured on both clocks (a round that
runs out of time lasts the 115 s round time plus the same end delay in every match, so the
clock that gives the same length in every file is the game's). Reads the raw JSON: the reader
itself keeps only the game clock (decoy_cli/esta/frames.py).
"""

from __future__ import annotations

import argparse
import json
import lzma
from pathlib import Path

import numpy as np

from decoy_cli.esta import collect_match_files


def study_file(path: Path) -> tuple[int, float, float, float]:
    """(tickRate, written rate, longest unplanted round on the game clock, on the written)."""
    opener = lzma.open if path.suffix == ".xz" else open
    with opener(path, "rt") as handle:
        document = json.load(handle)
    tick_rate = int(document["tickRate"])
    rates, game, written = [], [], []
    for round_ in document["gameRounds"]:
        frames = round_.get("frames") or []
        ticks = np.array([f["tick"] for f in frames], dtype=float)
        seconds = np.array([f["seconds"] for f in frames], dtype=float)
        if len(ticks) < 3:
            continue
        rate, zero = np.polyfit(seconds, ticks, 1)
        rates.append(rate)
        if round_.get("bombPlantTick") is None:
            game.append((ticks[-1] - zero) / tick_rate)
            written.append(seconds[-1])
    longest_game, longest_written = max(game, default=np.nan), max(written, default=np.nan)
    return tick_rate, float(np.median(rates)), longest_game, longest_written


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("folder", type=Path)
    args = parser.parse_args()
    files, _ = collect_match_files([args.folder])
    print(f"{'file':<14}{'tickRate':>9}{'written/s':>10}{'game s':>9}{'written s':>10}")
    rows = []
    for path in files:
        tick_rate, rate, longest_game, longest_written = study_file(path)
        rows.append((round(rate), longest_game, longest_written))
        print(
            f"{path.name[:12]:<14}{tick_rate:>9}{rate:>10.1f}{longest_game:>9.2f}"
            f"{longest_written:>10.2f}"
        )
    # the rounds that ran the clock out end 115 s + the end delay after freeze time: compare the
    # median of the files whose longest unplanted round is near that, by the rate they used
    for written_rate in sorted({r for r, _, _ in rows}):
        game = np.array([g for r, g, _ in rows if r == written_rate])
        seen = np.array([w for r, _, w in rows if r == written_rate])
        near = (game > 117) & (game < 123)
        print(
            f"files written at {written_rate}/s: longest unplanted round, median of "
            f"{int(near.sum())}: game clock {np.median(game[near]):.2f} s, "
            f"written seconds {np.median(seen[near]):.2f} s"
        )


if __name__ == "__main__":
    main()
