"""Studies of the game's damage rules on real hits (benchmarks/studies/damage_rules_check.py and
damage_rules_evaluation.py; tests/test_damage_rules.py and tests/test_hit_groups.py check them).

`check_rules`: the damage rules against recorded hits, does each weapon's table entry explain
real damage?

For every firearm hit between enemies in ESTA `damages` rows (the rows the DOG's samples use;
grenades, fire, the bomb, knives, friendly fire and world damage are left out and counted), the
rules predict the health damage from the weapon, the hit group, the distance and whether the
victim's armour took part (`armorDamage` > 0: the frames that would say what armour the victim
wore are not always there, and a hit on a protected group with armour always costs armour). Per
weapon: how many hits the rules reproduce exactly and within 1 HP, and the base damage each hit
implies (its median should sit just below the table's value: the game truncates). Hits through
walls (penetration) and hits after the armour ran out do less or more than predicted and show as
the misses.

`evaluate_rules`: the rules-grounded damage outcome model on real hits, leave-rounds-out.

The model: the hit group drawn from a `HitGroupModel` learned from the training hits, the damage
computed by the game's rules (decoy_cli/damage/rules.py), scaled down for the learned share of
bullets that pass through something first (`rules_damage.Penetration`), and capped at 100 HP, as
the DOG's target is. The protocol is the paper's generative one, made independent of one split:
the rounds are dealt into `FOLDS` folds; each fold's hits are predicted (`DRAWS` draws each) by
a model that saw the other folds only, so every hit is a test hit once. On the pooled predictions:

* mean Wasserstein distance between generated and real damage per (weapon, hit group) cell with
  at least `MIN_CELL` real hits (the real cell by real group, the generated one by drawn group,
  as `decoy_cli/modeling/scores.wasserstein_cells` defines it), and its largest cell;
* per weapon with at least `MIN_WEAPON_SAMPLES` hits, the total variation distance between the real
  and the drawn hit-group distributions;

and per fold the mean Wasserstein over the cells the fold has (mean and spread over folds).

The victim's armour: where the round has frames, they say it (`armor`, `helmet`). Events without
frames still tell some of it: a hit that costs armour says the victim wore it there (kevlar, and
a helmet on a head hit), and a head hit that costs none says there was no helmet (the rules take
armour from a helmet on every head hit). Where the hit does not say (a leg; kevlar under a bare
head), the victim wears armour with the training hits' share of armoured body hits of victims
whose side had the same buy type (awpy's `tBuyType`/`ctBuyType`: an eco round buys little
armour), and a drawn head hit on an armoured victim meets a helmet with the training share of
such head hits that met one.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import pandas as pd
from _damage_folds import MIN_CELL

from decoy_cli.damage.hit_groups import GROUPS, HitGroupModel
from decoy_cli.damage.rules import (
    ARMORED_GROUPS,
    WEAPON_RULES,
    implied_base_damage,
    rule_group,
    shot_damage,
)
from decoy_cli.damage.rules_damage import Penetration
from decoy_cli.esta import Round
from decoy_cli.modeling.damage_rows import classify_damages
from decoy_cli.modeling.network_evaluation import DRAWS
from decoy_cli.modeling.sample_set import MAX_DAMAGE_HP, SampleStats
from decoy_cli.modeling.scores import (
    MIN_WEAPON_SAMPLES,
    sampling_floor,
    tv_floor,
    wasserstein_cells,
)
from decoy_cli.modeling.split import FOLDS, deal_folds

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


MIN_SHARE_HITS = 5
"""Fewest training hits of a buy type for its own armour shares; fewer use all hits'."""


@dataclass(frozen=True)
class RulesEvaluation:
    """The pooled and per-fold results (module doc)."""

    hits: int
    rounds: int
    cells: pd.DataFrame
    """weapon, group, real, generated, wasserstein_hp and floor_hp (`scores.sampling_floor`)
    over the pooled test predictions."""
    mean_wasserstein_hp: float
    max_wasserstein_hp: float
    fold_mean_wasserstein_hp: list[float]
    group_tv: pd.DataFrame
    """weapon, hits, tv, tv_floor and tv_floor_above_0.15 (`scores.tv_floor`: its mean, and how
    often a model exactly right exceeds 0.15), and the real and drawn shares of every group."""
    armour_shares: dict[str, tuple[float, float]]
    """(kevlar share, helmet share) by the victim side's buy type over all hits, for the report
    (each fold's draws use the shares of its training folds only)."""


def _shares(hits: pd.DataFrame) -> tuple[float, float]:
    body = hits[hits["group"].isin(list(ARMORED_GROUPS))]
    head = hits[hits["group"] == "Head"]
    armored = float((body["armorDamage"] > 0).mean()) if len(body) else 0.0
    helmet = float((head["armorDamage"] > 0).mean()) if len(head) else 0.0
    return armored, helmet


def _armour_shares(train: pd.DataFrame) -> dict[str, tuple[float, float]]:
    """(kevlar share, helmet share) by buy type, and "" for all hits (module doc)."""
    shares = {"": _shares(train)}
    for buy, hits in train.groupby("victim_buy"):
        if len(hits) >= MIN_SHARE_HITS and buy:
            shares[str(buy)] = _shares(hits)
    return shares


def _victim_state(
    hit: pd.Series, shares: dict[str, tuple[float, float]], rng: np.random.Generator
) -> tuple[bool, bool]:
    """(kevlar, helmet) of the victim of a real hit (module doc)."""
    armored_share, helmet_share = shares.get(hit["victim_buy"], shares[""])
    costs_armour = bool(hit["armorDamage"] > 0)
    if hit["group"] in ARMORED_GROUPS:
        kevlar = costs_armour
    elif hit["group"] == "Head":  # a helmet takes armour on every head hit: the hit says it
        return costs_armour or bool(rng.random() < armored_share), costs_armour
    else:
        kevlar = bool(rng.random() < armored_share)
    return kevlar, kevlar and bool(rng.random() < helmet_share)


def evaluate_rules(rounds: Sequence[Round], seed: int = 0) -> RulesEvaluation:
    """Leave-rounds-out evaluation of the rules-grounded model on the rounds' damage events
    (module doc)."""
    tables = [
        r.damages.assign(round=f"{r.match_id}:{r.round_num}", victim_buy=_victim_buy(r))
        for r in rounds
    ]
    hits, _ = firearm_hits(pd.concat(tables, ignore_index=True))
    hits = hits.assign(group=[rule_group(g) for g in hits["hitGroup"]])
    rng = np.random.default_rng(seed)
    fold_of = deal_folds(hits["round"].tolist(), rng)
    hits["fold"] = hits["round"].map(fold_of)
    generated_rows = []
    fold_means = []
    for fold in range(FOLDS):
        train, test = hits[hits["fold"] != fold], hits[hits["fold"] == fold]
        if not len(test):
            continue
        model = HitGroupModel.fit(train["weapon"], train["distance"], train["group"])
        through = Penetration.learn(
            train["weapon"].tolist(), train["group"].tolist(), train["distance"].tolist(),
            train["hpDamage"].tolist(),
        )  # fmt: skip
        shares = _armour_shares(train)
        rows = []
        for _, hit in test.iterrows():
            kevlar, helmet = _victim_state(hit, shares, rng)
            for group in model.sample(rng, [hit["weapon"]] * DRAWS, [hit["distance"]] * DRAWS):
                damage = shot_damage(
                    hit["weapon"], group, hit["distance"], armor=100 if kevlar else 0, helmet=helmet
                ).health
                damage = int(damage * through.factor(rng))
                rows.append((hit["weapon"], group, min(damage, MAX_DAMAGE_HP)))
        generated = pd.DataFrame(rows, columns=["weapon", "group", "damage"])
        generated_rows.append(generated)
        cells = _cells(test, generated)
        if len(cells):
            fold_means.append(float(cells["wasserstein_hp"].mean()))
    generated = pd.concat(generated_rows, ignore_index=True)
    cells = _cells(hits, generated)
    return RulesEvaluation(
        hits=len(hits),
        rounds=len(fold_of),
        cells=cells,
        mean_wasserstein_hp=float(cells["wasserstein_hp"].mean()) if len(cells) else np.nan,
        max_wasserstein_hp=float(cells["wasserstein_hp"].max()) if len(cells) else np.nan,
        fold_mean_wasserstein_hp=fold_means,
        group_tv=_group_tv(hits, generated),
        armour_shares=_armour_shares(hits),
    )


def _victim_buy(round_: Round) -> pd.Series:
    """The buy type of each damage row's victim side ("" when unknown)."""
    sides = round_.damages.get("victimSide", pd.Series(dtype=object))
    return sides.map(lambda side: round_.buy_types.get(str(side), "")).fillna("")


def _cells(real: pd.DataFrame, generated: pd.DataFrame) -> pd.DataFrame:
    """Wasserstein per (weapon, group) cell with at least `MIN_CELL` real hits."""
    found = wasserstein_cells(
        real["weapon"].to_numpy(dtype=object),
        real["group"].map(GROUPS.index).to_numpy(),
        real["hpDamage"].clip(upper=MAX_DAMAGE_HP).to_numpy(np.float64),
        generated["weapon"].to_numpy(dtype=object),
        generated["group"].map(GROUPS.index).to_numpy(),
        generated["damage"].to_numpy(np.float64),
        min_cell=MIN_CELL,
    )
    weapon, group, damage = _by_draw(generated)
    floors = sampling_floor(found, weapon, group, damage)
    rows = [
        (c.weapon, c.part, c.real, c.generated, c.wasserstein_hp, floor)
        for c, floor in zip(found, floors, strict=True)
    ]
    columns = ["weapon", "group", "real", "generated", "wasserstein_hp", "floor_hp"]
    return pd.DataFrame(rows, columns=columns)


def _by_draw(generated: pd.DataFrame) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The generated rows (`DRAWS` consecutive rows per hit) as (K,) weapons and (DRAWS, K)
    hit-group codes and damage, the layout of `scores.sampling_floor`."""
    k = len(generated) // DRAWS
    group = generated["group"].map(GROUPS.index).to_numpy().reshape(k, DRAWS).T
    damage = generated["damage"].to_numpy(np.float64).reshape(k, DRAWS).T
    return generated["weapon"].to_numpy(dtype=object)[::DRAWS], group, damage


def _group_tv(real: pd.DataFrame, generated: pd.DataFrame) -> pd.DataFrame:
    """Per weapon with enough hits: total variation between real and drawn group shares."""
    drawn_weapon, drawn_groups, _ = _by_draw(generated)
    rows = []
    for weapon, group in real.groupby("weapon"):
        if len(group) < MIN_WEAPON_SAMPLES:
            continue
        p = group["group"].value_counts(normalize=True).reindex(GROUPS, fill_value=0.0)
        drawn = generated[generated["weapon"] == weapon]["group"]
        q = drawn.value_counts(normalize=True).reindex(GROUPS, fill_value=0.0)
        tv = 0.5 * float((p - q).abs().sum())
        floor, above = tv_floor(drawn_groups[:, drawn_weapon == weapon])
        rows.append(
            {"weapon": weapon, "hits": len(group), "tv": tv, "tv_floor": floor,
             "tv_floor_above_0.15": above}
        )  # fmt: skip
        rows[-1] |= {f"real_{g}": float(p[g]) for g in GROUPS}
        rows[-1] |= {f"drawn_{g}": float(q[g]) for g in GROUPS}
    return pd.DataFrame(rows)
