"""The stairs between Under A and A in CS2's de_dust2 (docs/cs2.md, "Climbs"): the nav's areas
there and the rises between connected ones, and how real players' heights change there in the
round recorded at 8 frames a second.

    python benchmarks/studies/cs2_stairs.py
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from decoy_cli.csgo import HAMMER_TO_M
from decoy_cli.esta import read_match
from decoy_cli.world.nav_json import read_nav

DATA = Path(__file__).resolve().parents[2].parent / "shared" / "data"
NAV = DATA / "cs2_maps" / "de_dust2.nav.json.xz"
ROUND_8HZ = DATA / "cs2_dust2_both" / "spirit-vs-falcons-m2-dust2-8hz-r02.json.xz"
STAIRS_U = (560.0, 760.0, 2290.0, 2430.0)
"""x from, x to, y from, y to (Hammer units): the stairs and their landings."""


def inside(xy: np.ndarray) -> np.ndarray:
    x0, x1, y0, y1 = STAIRS_U
    return (xy[..., 0] >= x0) & (xy[..., 0] <= x1) & (xy[..., 1] >= y0) & (xy[..., 1] <= y1)


def main() -> None:
    nav = read_nav(NAV)
    areas = [a for a in range(nav.num_areas) if inside(nav.polygon(a).mean(axis=0))]
    print("area  id    floor z (u)   depth (u: the shorter side of its bounding box)")
    for a in areas:
        polygon = nav.polygon(a)
        size = polygon[:, :2].max(axis=0) - polygon[:, :2].min(axis=0)
        z = polygon[:, 2]
        print(f"{a:5d} {nav.area_id[a]:5d} {z.min():6.0f}..{z.max():<6.0f} {size.min():6.1f}")
    inner = set(areas)
    rises = [
        float(nav.polygon(b)[:, 2].mean() - nav.polygon(a)[:, 2].mean())
        for a, b in nav.connections.tolist()
        if a in inner and b in inner
    ]
    ups = sorted(round(r) for r in rises if r > 0)
    print(f"rises between connected areas there (u, mean floor heights): {ups}")

    match = read_match(ROUND_8HZ)
    for round_ in match.rounds:
        position = round_.position / HAMMER_TO_M  # (players, frames, 3), units
        for p, player in enumerate(round_.players):
            on = inside(position[p]) & round_.alive[p]
            if on.sum() < 2:
                continue
            z = position[p, on, 2]
            steps = np.diff(z)
            print(
                f"round {round_.round_num} {player.name}: {on.sum()} frames on the stairs, "
                f"height {z.min():.0f}..{z.max():.0f} u, largest rise between frames "
                f"{steps.max():.0f} u, rises over 10 u: {[round(s) for s in steps if s > 10]}"
            )


if __name__ == "__main__":
    main()
