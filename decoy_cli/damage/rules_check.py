"""The damage rules against recorded hits: does each weapon's table entry explain real damage?

For every firearm hit between enemies in ESTA `damages` rows (the rows the DOG's samples use;
grenades, fire, the bomb, knives, friendly fire and world damage are left out and counted), the
rules predict the health damage from the weapon, the hit group, the distance and whether the
victim's armour took part (`armorDamage` > 0: the frames that would say what armour the victim
wore are not always there, and a hit on a protected group with armour always costs armour). Per
weapon: how many hits the rules reproduce exactly and within 1 HP, and the base damage each hit
implies (its median should sit just below the table's value: the game truncates). Hits through
walls (penetration) and hits after the armour ran out do less or more than predicted and show as
the misses.
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from decoy_cli.damage.damage_rows import classify_damages
from decoy_cli.damage.rules import (
    WEAPON_RULES,
    implied_base_damage,
    rule_group,
    shot_damage,
)
from decoy_cli.damage.sample_set import SampleStats

CHECK_COLUMNS = (
    "weapon",
    "hits",
    "damage",
    "exact_share",
    "within_1hp_share",
    "implied_median",
    "implied_p10",
    "implied_p90",
)
"""One row per weapon, most hits first."""

FULL_ARMOR = 100


def firearm_hits(damages: pd.DataFrame) -> tuple[pd.DataFrame, dict[str, int]]:
    """The rows the rules apply to: the firearm damage between enemies the DOG's samples use
    (`damage_rows.classify_damages`: raw damage and hit group known) that has a distance; and
    the rows left out by reason."""
    stats = SampleStats()
    rows = classify_damages(damages, stats)
    distance = pd.to_numeric(damages["distance"], errors="coerce").to_numpy(np.float64)
    usable = rows.outcome_known & np.isfinite(distance)
    left_out = dict(stats.excluded) | dict(stats.partial)
    if int((rows.outcome_known & ~usable).sum()):
        left_out["no distance"] = int((rows.outcome_known & ~usable).sum())
    return damages[usable].reset_index(drop=True), left_out


def check_rules(damages: pd.DataFrame) -> tuple[pd.DataFrame, dict[str, int]]:
    """Per weapon, how well the rules explain the recorded hits (module doc), and the rows
    left out by reason."""
    hits, left_out = firearm_hits(damages)
    predicted, implied = [], []
    for row in hits.itertuples(index=False):
        armored = row.armorDamage > 0
        group = rule_group(row.hitGroup)
        hit = shot_damage(
            row.weapon, group, row.distance, armor=FULL_ARMOR if armored else 0, helmet=armored
        )
        predicted.append(hit.health)
        implied.append(implied_base_damage(row.weapon, group, row.distance, row.hpDamage, armored))
    hits = hits.assign(predicted=predicted, implied=implied)
    rows = []
    for weapon, group in hits.groupby("weapon"):
        error = group["hpDamage"].to_numpy() - group["predicted"].to_numpy()
        values = group["implied"].to_numpy(np.float64)
        rows.append(
            {
                "weapon": weapon,
                "hits": len(group),
                "damage": WEAPON_RULES[str(weapon)].damage,
                "exact_share": float(np.mean(error == 0)),
                "within_1hp_share": float(np.mean(np.abs(error) <= 1)),
                "implied_median": float(np.median(values)),
                "implied_p10": float(np.percentile(values, 10)),
                "implied_p90": float(np.percentile(values, 90)),
            }
        )
    table = pd.DataFrame(rows, columns=list(CHECK_COLUMNS))
    return table.sort_values(["hits", "weapon"], ascending=[False, True]).reset_index(
        drop=True
    ), left_out
