"""Extract the ladders of a map from CS:GO `.nav` files into `assets/<map>/nav_ladders.csv`.

Run once by a maintainer, for the maps whose nav mesh has ladders:

    python scripts/extract_nav_ladders.py --map nuke FILE.nav [FILE.nav ...]

awpy 1.3.1's nav data has no ladders; the game's `.nav` file has them (`decoy_cli.world.nav_file`).
Give the map's official file (`csgo/maps/<map>.nav` of a CS:GO install) or, as the shipped
assets did, several independent copies: only the ladders every file agrees on (same id, ends
within 1 u) are written, so a ladder one editor added is left out. The files shipped were made
from two published copies (see each map's ATTRIBUTION.md); a map without ladders gets no file
(an old one is removed).
"""

from __future__ import annotations

import argparse
import csv
from pathlib import Path

import numpy as np

from decoy_cli.waypoints.build import canonical_map
from decoy_cli.world.nav_data import NAV_LADDERS_FILE, asset_dir
from decoy_cli.world.nav_file import LADDER_COLUMNS, read_nav_ladders

AGREE_U = 1.0
"""How close (Hammer units) two files' ends of the same ladder must be to count as agreeing."""


def agreed(sets: list[np.ndarray]) -> np.ndarray:
    """The ladders of the first set that every other set has too (same id, ends within 1 u)."""
    keep = []
    for ladder in sets[0]:
        if all(
            any(o[0] == ladder[0] and np.all(np.abs(o[2:] - ladder[2:]) <= AGREE_U) for o in other)
            for other in sets[1:]
        ):
            keep.append(ladder)
    return np.asarray(keep).reshape(-1, len(LADDER_COLUMNS))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--map", required=True)
    parser.add_argument("nav_files", nargs="+", type=Path)
    args = parser.parse_args()
    map_name = canonical_map(args.map)
    sets = [read_nav_ladders(path) for path in args.nav_files]
    ladders = agreed(sets)
    for path, found in zip(args.nav_files, sets, strict=True):
        print(f"{path}: {len(found)} ladders")
    out = asset_dir(map_name) / NAV_LADDERS_FILE
    if not len(ladders):
        out.unlink(missing_ok=True)
        print(f"{map_name}: no ladders all files agree on; no {NAV_LADDERS_FILE}")
        return
    with open(out, "w", newline="") as f:
        writer = csv.writer(f, lineterminator="\n")
        writer.writerow(LADDER_COLUMNS)
        for row in ladders:
            writer.writerow([int(row[0]), *(f"{v:.3f}".rstrip("0").rstrip(".") for v in row[1:])])
    print(f"{map_name}: {len(ladders)} ladders -> {out}")


if __name__ == "__main__":
    main()
