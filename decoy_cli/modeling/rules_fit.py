"""Fitting the rules-grounded model's learned parts (`decoy models fit-rules`): the hit groups,
the bullets per step and the penetration that a model folder's `rules.json` holds
(decoy_cli/damage/rules_damage.py applies them in the fight).

Hits whose data records only the HP lost still count toward the hit groups: `group_posterior`
weighs each group by how well the game's rules (decoy_cli/damage/rules.py) explain that loss.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from decoy_cli.damage.bullet_counts import ALL, BulletCounts
from decoy_cli.damage.hit_groups import GROUPS, HitGroupModel
from decoy_cli.damage.rules import shot_damage
from decoy_cli.damage.rules_damage import FULL_HP, Penetration, RulesFile
from decoy_cli.errors import ModelError
from decoy_cli.esta import Round
from decoy_cli.modeling.damage_rows import DamageRows, aggregate, damage_rows, step_clock
from decoy_cli.modeling.sample_set import SampleStats

HP_LOST_SPREAD = 0.15
"""Relative spread of a hit's HP lost around what the rules give for its group when no group
gives it exactly (the rules know neither the armour left nor a shot through thin cover, and a
map's version may deal a little less; chosen a priori)."""

MAX_MISS_SPREADS = 3.0
"""A non-lethal hit further than this many spreads from every group's rule damage is left
unexplained (a shot through something; chosen a priori)."""


def group_posterior(
    prior: HitGroupModel,
    weapon: str,
    distance_u: float,
    hp_lost: float,
    hp_before: float,
    armored: bool,
) -> np.ndarray | None:
    """(6,) P(group | a hit's HP lost) for a hit whose data records no hit group: the prior's
    P(group | weapon, distance) times the likelihood of the HP lost under each group's rule
    damage (decoy_cli/damage/rules.py). A hit that killed lost the victim's HP: any group the
    rules give at least that much explains it. A hit that left the victim alive is explained
    by the groups the rules give within 1 HP; when none does, by how close each comes (a normal
    of `HP_LOST_SPREAD` relative width, up to `MAX_MISS_SPREADS`): keeping only exact matches
    kept the kills, which any head shot explains, and dropped body hits the rules miss by a few
    HP, leaning the groups toward the head. None when no group explains it."""
    value = np.array(
        [
            shot_damage(
                weapon, name, distance_u, armor=100 if armored else 0, helmet=armored
            ).health
            for name in GROUPS
        ],
        dtype=np.float64,
    )
    if hp_lost >= hp_before - 0.5:  # killed
        likelihood = (value >= hp_lost - 0.5).astype(np.float64)
    elif (np.abs(value - hp_lost) <= 1.0).any():
        likelihood = (np.abs(value - hp_lost) <= 1.0).astype(np.float64)
    else:
        z = (value - hp_lost) / np.maximum(1.0, HP_LOST_SPREAD * value)
        likelihood = np.where(np.abs(z) <= MAX_MISS_SPREADS, np.exp(-0.5 * z * z), 0.0)
    weights = prior.probabilities(weapon, distance_u) * likelihood
    if weights.sum() <= 0:
        return None
    return weights / weights.sum()


def fit_rules(rounds: Sequence[Round]) -> RulesFile:
    """Learn the hit groups, the penetration and the bullets per step from the rounds' firearm
    hits: the damage rows the DOG's samples use (`damage_rows`). Bullets are counted per
    (attacker, victim) and virtual 2 Hz step exactly as the events mode aggregates them, so a
    step here is a sample's step, from every hit (also those whose data records only the HP
    lost); hit groups and penetration from the hits whose raw damage and hit group are known."""
    stats = SampleStats()
    weapons: list[str] = []
    distances: list[float] = []
    groups: list[str] = []
    health: list[float] = []
    bullets, bullets_hurt = BulletCounts(censored=True), BulletCounts(censored=True)
    unknown: list[tuple[str, float, float, float, bool]] = []
    used_rounds = 0
    maps: set[str] = set()
    for round_ in rounds:
        rows = damage_rows(round_, stats)
        distance = round_.damages["distance"].to_numpy(np.float64, na_value=np.nan)
        usable = rows.usable & np.isfinite(distance)
        if not usable.any():
            continue
        used_rounds += 1
        maps.add(round_.map_name)
        known = np.flatnonzero(usable & rows.outcome_known)
        unknown += _hp_lost_hits(round_, rows, usable & ~rows.outcome_known, distance)
        table = round_.damages.iloc[known]
        weapons += [str(w) for w in table["weapon"]]
        distances += [float(d) for d in table["distance"]]
        groups += [str(g) for g in table["hitGroup"]]
        health += [float(h) for h in table["hpDamage"]]
        origin, step_ticks = step_clock(round_)
        # a row without a tick (never usable) says nothing of when its HP was lost: no step
        step = np.where(np.isfinite(rows.tick), np.rint((rows.tick - origin) / step_ticks), np.inf)
        steps = aggregate(step, rows.attacker, rows.victim, rows, np.flatnonzero(usable))
        for (at, _, _), hit in steps.items():
            victim = rows.victim == rows.victim[hit.first]
            lost = float(rows.hp_taken[victim & (rows.tick < rows.tick[hit.first])].sum())
            # died in the step, by this attacker's bullets or another's: its count was cut short
            killed = float(rows.hp_taken[victim & (step <= at)].sum()) >= FULL_HP - 0.5
            counts = bullets_hurt if lost > 0 else bullets
            counts.add(str(rows.weapon[hit.first]), float(distance[hit.first]), hit.hits, killed)
    total = sum(sum(c.counts.get(ALL, [])) for c in (bullets, bullets_hurt))
    if not total:
        raise ModelError("no firearm hits between enemies in the data: nothing to learn from")
    if not weapons:
        raise ModelError(
            "no firearm hit in the data records its hit group and raw damage: the hit groups "
            "and penetration cannot be learned"
        )
    model = HitGroupModel.fit(weapons, distances, groups)
    prior = HitGroupModel.from_dict(model.to_dict())
    explained = 0
    for weapon, distance, lost, before, armored in unknown:
        weights = group_posterior(prior, weapon, distance, lost, before, armored)
        if weights is not None:
            model.add(weapon, distance, weights)
            explained += 1
    penetration = Penetration.learn(weapons, groups, distances, health)
    provenance = {
        "hits": len(weapons),
        "hits_by_hp_lost": explained,
        "hits_unexplained": len(unknown) - explained,
        "steps": int(total),
        "rounds": used_rounds,
        "maps": sorted(maps),
        "left_out": dict(stats.excluded),
        "hp_lost_only": dict(stats.partial),
    }
    return RulesFile(model, bullets, provenance, penetration, bullets_hurt)


def _hp_lost_hits(
    round_: Round, rows: DamageRows, chosen: np.ndarray, distance: np.ndarray
) -> list[tuple[str, float, float, float, bool]]:
    """(weapon, distance, HP lost, victim's HP before, armour took part) of the `chosen` rows,
    hits whose data records only the HP lost."""
    out = []
    for r in np.flatnonzero(chosen):
        earlier = (rows.victim == rows.victim[r]) & (rows.tick < rows.tick[r])
        before = 100.0 - float(rows.hp_taken[earlier].sum())
        armored = bool(rows.armor_damage[r] > 0)
        lost = float(rows.hp_taken[r])
        out.append((str(rows.weapon[r]), float(distance[r]), lost, before, armored))
    return out
