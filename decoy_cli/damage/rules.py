"""CS:GO's damage rules: what one bullet does, given the weapon, where it hit, how far it flew
and the victim's armour.

The game decides the amount; only whether a shot lands and where are chance. A
bullet's damage is

    base × range_modifier ^ (distance / 500 u) × hit-group multiplier

then, when the victim wears armour and the hit group is protected by it (chest, stomach, arms,
neck; the head only with a helmet; never the legs), the health takes `armor_ratio / 2` of it and
the armour half of the rest (the armour can only give what it has; beyond that the health takes
the rest), and finally the health damage is truncated to an integer (`shot_damage`). The victim's
remaining health caps what it loses (ESTA's `hpDamageTaken`); the uncapped value is `hpDamage`.

Sources:

* weapon values (`WEAPON_RULES`): the weapon attributes of CS:GO's `items_game.txt` ("damage",
  "armor ratio", "range modifier", "bullets"; "headshot multiplier" 4 unless the weapon sets it)
  of the 2020 game version, the version of the real events in `../shared/data`; each value is
  checked against those events by `implied_base_damage` (`python
  benchmarks/studies/damage_rules_check.py DATA` prints the check; docs/damage-models.md gives
  its result). `checked` says which ones were;
* hit-group multipliers and the armour rule: CS:GO's `CCSPlayer::TraceAttack` and
  `CCSPlayer::OnTakeDamage` (head ×4 by the weapon's multiplier, stomach ×1.25, legs ×0.75,
  chest, arms and neck ×1; armour bonus ratio 0.5), confirmed by the same events (an AK-47 chest
  hit at 800 u does 34 HP unarmoured, 27 HP and 3 armour armoured).

Bullet penetration through walls and objects lowers damage further; the world has no materials,
so a replay's shots never go through walls and the rule gives the unobstructed value.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

RANGE_UNIT_U = 500.0
"""The range modifier applies once per this many Hammer units of flight."""

ARMOR_BONUS = 0.5
"""Armour lost per point of damage it absorbs, as the game counts it."""

HIT_GROUP_MULTIPLIER = {
    "Chest": 1.0,
    "Stomach": 1.25,
    "Arm": 1.0,
    "Leg": 0.75,
    "Neck": 1.0,
}
"""Damage multipliers of the hit groups other than the head (the head's is the weapon's)."""

ARMORED_GROUPS = frozenset({"Chest", "Stomach", "Arm", "Neck"})
"""Hit groups body armour protects; the head needs a helmet, legs are never protected."""

HIT_GROUP_ALIASES = {"LeftArm": "Arm", "RightArm": "Arm", "LeftLeg": "Leg", "RightLeg": "Leg"}
"""ESTA's left/right groups, folded into the rule's groups."""


@dataclass(frozen=True)
class WeaponRules:
    """One weapon's damage facts (module doc)."""

    damage: int
    armor_ratio: float
    range_modifier: float
    headshot_multiplier: float = 4.0
    bullets: int = 1
    """Pellets per shot (shotguns); each pellet is a hit of its own."""
    checked: bool = False
    """True when the real events confirm the values (module doc)."""


WEAPON_RULES: dict[str, WeaponRules] = {
    # pistols
    "Glock-18": WeaponRules(30, 0.94, 0.85, checked=True),
    "USP-S": WeaponRules(35, 1.01, 0.91, checked=True),
    "P2000": WeaponRules(35, 1.01, 0.91),
    "P250": WeaponRules(38, 1.28, 0.90, checked=True),
    "Dual Berettas": WeaponRules(38, 1.15, 0.79),
    "Five-SeveN": WeaponRules(32, 1.823, 0.81),
    "Tec-9": WeaponRules(33, 1.812, 0.79, checked=True),
    "CZ75 Auto": WeaponRules(31, 1.553, 0.85, checked=True),
    "Desert Eagle": WeaponRules(63, 1.864, 0.81, checked=True),
    "R8 Revolver": WeaponRules(86, 1.864, 0.94),
    # SMGs
    "MAC-10": WeaponRules(29, 1.15, 0.80, checked=True),
    "MP9": WeaponRules(26, 1.20, 0.87, checked=True),
    "MP7": WeaponRules(29, 1.25, 0.85),
    "MP5-SD": WeaponRules(27, 1.25, 0.85),
    "UMP-45": WeaponRules(35, 1.30, 0.75, checked=True),
    "P90": WeaponRules(26, 1.38, 0.86),
    "PP-Bizon": WeaponRules(27, 1.15, 0.80),
    # rifles (awpy calls the M4A1-S "M4A1")
    "AK-47": WeaponRules(36, 1.55, 0.98, checked=True),
    "M4A4": WeaponRules(33, 1.40, 0.97, checked=True),
    "M4A1": WeaponRules(38, 1.40, 0.94),
    "Galil AR": WeaponRules(30, 1.55, 0.98, checked=True),
    "FAMAS": WeaponRules(30, 1.40, 0.96, checked=True),
    "SG 553": WeaponRules(30, 2.00, 0.98),
    "AUG": WeaponRules(28, 1.80, 0.98, checked=True),
    "SSG 08": WeaponRules(88, 1.70, 0.98, checked=True),
    "AWP": WeaponRules(115, 1.95, 0.99, checked=True),
    "G3SG1": WeaponRules(80, 1.65, 0.98),
    "SCAR-20": WeaponRules(80, 1.65, 0.98),
    # heavy
    "Nova": WeaponRules(26, 1.00, 0.70, bullets=9),
    "XM1014": WeaponRules(20, 1.60, 0.70, bullets=6),
    "MAG-7": WeaponRules(30, 1.50, 0.45, bullets=8),
    "Sawed-Off": WeaponRules(32, 1.50, 0.45, bullets=8),
    "M249": WeaponRules(32, 1.60, 0.97),
    "Negev": WeaponRules(35, 1.42, 0.97),
}
"""Damage facts of every firearm, by the display name ESTA uses (module doc for the source)."""


class UnknownWeaponError(ValueError):
    """A weapon the rule table lacks (a knife, grenade, Zeus or a name from another version)."""


@dataclass(frozen=True)
class Hit:
    """What one bullet takes: health (integer, before the victim's health caps it) and armour."""

    health: int
    armor: int


def rules_for(weapon: str) -> WeaponRules:
    """The weapon's facts; an `UnknownWeaponError` naming it when the table lacks it."""
    try:
        return WEAPON_RULES[weapon]
    except KeyError:
        raise UnknownWeaponError(f"no damage rules for the weapon {weapon!r}") from None


def rule_group(hit_group: str) -> str:
    """ESTA's hit group as the rules name it ("LeftArm" is "Arm"); unknown names raise."""
    group = HIT_GROUP_ALIASES.get(hit_group, hit_group)
    if group != "Head" and group not in HIT_GROUP_MULTIPLIER:
        raise ValueError(f"no damage rule for the hit group {hit_group!r}")
    return group


def raw_damage(weapon: str, hit_group: str, distance_u: float) -> float:
    """The bullet's damage before armour: base, range falloff and hit-group multiplier."""
    rules = rules_for(weapon)
    group = rule_group(hit_group)
    multiplier = rules.headshot_multiplier if group == "Head" else HIT_GROUP_MULTIPLIER[group]
    falloff = rules.range_modifier ** (max(distance_u, 0.0) / RANGE_UNIT_U)
    return rules.damage * falloff * multiplier


def is_protected(hit_group: str, armor: int, helmet: bool) -> bool:
    """Whether the victim's armour takes part in a hit on this group."""
    group = rule_group(hit_group)
    return armor > 0 and (group in ARMORED_GROUPS or (group == "Head" and helmet))


def shot_damage(weapon: str, hit_group: str, distance_u: float, *, armor: int, helmet: bool) -> Hit:
    """Health and armour one bullet takes by the game's rules (module doc)."""
    damage = raw_damage(weapon, hit_group, distance_u)
    if not is_protected(hit_group, armor, helmet):
        return Hit(health=int(damage), armor=0)
    to_health = damage * rules_for(weapon).armor_ratio * 0.5
    to_armor = (damage - to_health) * ARMOR_BONUS
    if to_armor > armor:
        to_health = damage - armor / ARMOR_BONUS
        to_armor = armor
    return Hit(health=int(to_health), armor=int(to_armor))


def apply_hit(health: int, armor: int, hit: Hit) -> tuple[int, int]:
    """The victim's health and armour after the hit: neither goes below zero (ESTA's
    `hpDamageTaken` is what the health lost)."""
    return max(health - hit.health, 0), max(armor - hit.armor, 0)


def implied_base_damage(
    weapon: str, hit_group: str, distance_u: float, health_damage: float, armored: bool
) -> float:
    """The base damage a recorded hit implies under the rules (the weapon's falloff, the group's
    multiplier, the armour ratio when `armored`): it clusters just below the weapon's `damage`
    (the game truncates) when the facts are right; wall-bangs and armour that ran out fall below."""
    rules = rules_for(weapon)
    unit = raw_damage(weapon, hit_group, distance_u) / rules.damage
    if armored:
        unit *= rules.armor_ratio * 0.5
    return health_damage / unit if unit > 0 else math.nan
