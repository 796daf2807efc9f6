"""The fire's damage rate measured on real events: how often a fire's damage rows come and how
many HP each takes (decoy_cli/sim/utility.py's `FIRE_HP_PER_S`).

    python benchmarks/studies/utility_constants.py

Reads the damage rows of ../shared/data/esta_dust2_events and ../shared/data/events_ancient
whose weapon is a Molotov or an Incendiary Grenade, and prints the seconds between a victim's
consecutive fire rows (quantiles) and the HP per row where the data records it (awpy's
`hpDamage`): a player fully in the flames loses the largest of them at every row.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd

SHARED = Path(__file__).resolve().parents[2].parent / "shared" / "data"
FIRE_WEAPONS = ("Molotov", "Incendiary Grenade")


def main() -> None:
    from decoy_cli.esta import iter_match_files, read_match

    tables = []
    for folder in ("esta_dust2_events", "events_ancient"):
        for path in iter_match_files(SHARED / folder):
            match = read_match(path)
            for round_ in match.rounds:
                fire = round_.damages[round_.damages["weapon"].isin(FIRE_WEAPONS)]
                key = f"{match.match_id}:{round_.round_num}"
                tables.append(fire.assign(round_key=key, tick_rate=match.tick_rate))
    fire = pd.concat(tables, ignore_index=True)
    gaps: list[float] = []
    for _, rows in fire.sort_values("tick").groupby(["round_key", "victimName"]):
        seconds = rows["tick"].to_numpy(np.float64) / rows["tick_rate"].iloc[0]
        gaps += np.diff(seconds).tolist()
    hp = fire["hpDamage"].dropna().astype(int)
    quantiles = np.percentile(gaps, [10, 25, 50, 75, 90])
    print(f"{len(fire)} fire damage rows ({fire['weapon'].value_counts().to_dict()})")
    print(
        "seconds between a victim's rows, 10/25/50/75/90%: "
        + ", ".join(f"{q:.3f}" for q in quantiles)
    )
    print(f"HP per row where recorded ({len(hp)} rows): most {hp.max()}, median {hp.median():g}")
    print(f"the most a second: {hp.max() / np.median(gaps):.1f} HP")


if __name__ == "__main__":
    main()
