"""The fall-damage rule against real health losses at falls:
python benchmarks/studies/fall_damage_check.py [FOLDER]   (default ../shared/data/esta_dust2_tside)

A fall is a drop of the player's height by more than the safe 210 u within one or two data
frames (0.5-1 s) while the player stays alive. Data at 2 frames per second does not show the
apex, so each fall is compared with the rule for a fall from rest through the height lost and
for one after a jump (57 u more); health lost to an enemy in the same second (unrecorded CT
shots) shows as outliers, so the comparison is by medians per height band.
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

from decoy_cli.csgo import HAMMER_TO_M, SAFE_DROP_M, fall_damage
from decoy_cli.esta import iter_match_files, read_match

JUMP_U = 57.0
BANDS_U = ((210, 240), (240, 270), (270, 300), (300, 400))


def falls(folder: Path) -> np.ndarray:
    """(K, 2): height lost (u) and health lost at every fall in the folder's rounds."""
    rows = []
    for path in iter_match_files(folder):
        for round_ in read_match(path).rounds:
            z = round_.position[:, :, 2] / HAMMER_TO_M
            hp = round_.hp.astype(float)
            for player in range(z.shape[0]):
                frame = 0
                while frame < z.shape[1] - 1:
                    for width in (1, 2):
                        end = frame + width
                        if end >= z.shape[1]:
                            break
                        drop = z[player, frame] - z[player, end]
                        if drop > SAFE_DROP_M / HAMMER_TO_M and hp[player, end] > 0:
                            rows.append((drop, hp[player, frame] - hp[player, end]))
                            frame = end
                            break
                    frame += 1
    return np.asarray(rows, dtype=np.float64).reshape(-1, 2)


def main() -> None:
    default = Path(__file__).parents[2].parent / "shared" / "data" / "esta_dust2_tside"
    folder = Path(sys.argv[1]) if len(sys.argv) > 1 else default
    found = falls(folder)
    print(f"{len(found)} falls deeper than 210 u in {folder}")
    print("height (u)   falls  health lost: median   rule from rest   rule after a jump")
    for low, high in BANDS_U:
        band = found[(found[:, 0] >= low) & (found[:, 0] < high)]
        if not len(band):
            continue
        middle = float(np.median(band[:, 0]))
        rest = fall_damage(middle * HAMMER_TO_M)
        jump = fall_damage((middle + JUMP_U) * HAMMER_TO_M)
        print(
            f"{low:>4}-{high:<4}   {len(band):>5}  {np.median(band[:, 1]):>18.1f}   "
            f"{rest:>14d}   {jump:>17d}"
        )


if __name__ == "__main__":
    main()
