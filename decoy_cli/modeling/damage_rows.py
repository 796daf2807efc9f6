"""The damage rows of a round, classified for both sample modes, and their sum per pair and step.

Which damage counts (both modes): firearm damage between enemies. Left out, with the reason
counted in `SampleStats.excluded`: world damage (no attacker), friendly fire, grenade, fire and
bomb damage (weaponClass "Grenade" or hitGroup "Generic"), weapons outside the models'
vocabulary (`features.WEAPONS`: knife, Zeus, C4) and rows without any damage value, victim or
tick. A row without a hit group or a raw `hpDamage` (data that records only the HP lost, such as
`events_ancient`) still says that the pair hit and how much HP it cost: it is `usable` (a hit,
its HP lost) but not `outcome_known` (what a DOG learns from: raw damage and hit group), and is
counted in `SampleStats.partial` with what it lacks.

Damage value: `hpDamage` (the raw HP damage of the hit, before the victim's remaining HP caps
it), summed over the hits of one pair in one step and capped at 100. Not `hpDamageTaken`: that
is capped by the victim's remaining HP, which is not a model input, so a DOG trained on it
would learn that an AK-47 chest hit does 20 HP whenever victims happened to be low. The
simulator applies DOG's damage capped at the victim's HP (decoy_cli/damage/combat.py), which
gives back exactly ESTA's hpDamageTaken; above 100 every value kills anyone, so the cap loses
nothing and keeps the target in [0, 1] HP/100. (The paper sums raw hpDamage without the cap.)
Hit group: the six groups of `HIT_GROUPS` (Left/RightArm -> Arm, Left/RightLeg -> Leg); for a
pair hit several times in one step, the group of its largest hit (the first such on a tie).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pandas as pd

from decoy_cli.damage.features import WEAPONS
from decoy_cli.damage.rules import HIT_GROUP_ALIASES
from decoy_cli.esta import Round
from decoy_cli.modeling.sample_set import MAX_DAMAGE_HP, SampleStats
from decoy_cli.sim.combat import HIT_GROUPS

_HIT_GROUP_CODE = {
    name: HIT_GROUPS.index(HIT_GROUP_ALIASES.get(name, name))
    for name in (*HIT_GROUPS, *HIT_GROUP_ALIASES)
}

VOCABULARY = frozenset(WEAPONS)
"""The firearms the models know (`features.WEAPONS`)."""


def player_keys(table: pd.DataFrame, owner: str) -> np.ndarray:
    """(N,) object array of player keys (steamID string, else name; None when unknown)."""
    ids = table[f"{owner}SteamID"].to_numpy(dtype=object, na_value=None)
    names = table[f"{owner}Name"].to_numpy(dtype=object, na_value=None)
    out = np.empty(len(table), dtype=object)
    for i, (steam_id, name) in enumerate(zip(ids, names, strict=True)):
        if steam_id is not None and int(steam_id) != 0:
            out[i] = str(int(steam_id))
        elif isinstance(name, str) and name:
            out[i] = name
        else:
            out[i] = None
    return out


def strings(table: pd.DataFrame, column: str) -> np.ndarray:
    """A string column as an object array with "" for nulls."""
    values = table[column].to_numpy(dtype=object, na_value=None)
    return np.array([v if isinstance(v, str) else "" for v in values], dtype=object)


def ints(table: pd.DataFrame, column: str) -> np.ndarray:
    """A nullable integer column as float64 with NaN for nulls."""
    return table[column].to_numpy(dtype=np.float64, na_value=np.nan)


@dataclass(frozen=True)
class DamageRows:
    """The damage rows of a round with what sample building needs, and which rows are usable."""

    tick: np.ndarray  # float64, NaN when null
    attacker: np.ndarray  # object keys or None
    victim: np.ndarray
    weapon: np.ndarray
    hp_damage: np.ndarray  # float64
    hp_taken: np.ndarray  # float64 HP lost (hpDamageTaken, else hpDamage; NaN -> 0 when summed)
    armor_damage: np.ndarray  # float64
    group_code: np.ndarray  # int64, -1 when none
    usable: np.ndarray  # bool: a firearm hit between enemies with its HP lost
    outcome_known: np.ndarray  # bool: usable, with its raw damage and hit group


def damage_rows(round_: Round, stats: SampleStats) -> DamageRows:
    """Classify every damage row of the round (module docstring), counting the reasons."""
    return classify_damages(round_.damages, stats)


def classify_damages(table: pd.DataFrame, stats: SampleStats) -> DamageRows:
    """Classify every row of an ESTA damages table (module docstring) and count the reasons
    for leaving one out."""
    attacker = player_keys(table, "attacker")
    victim = player_keys(table, "victim")
    weapon = strings(table, "weapon")
    weapon_class = strings(table, "weaponClass")
    hit_group = strings(table, "hitGroup")
    attacker_side = strings(table, "attackerSide")
    victim_side = strings(table, "victimSide")
    friendly = table["isFriendlyFire"].to_numpy(dtype=object, na_value=None)
    hp_damage = ints(table, "hpDamage")
    hp_taken = ints(table, "hpDamageTaken")
    hp_taken = np.where(np.isfinite(hp_taken), hp_taken, hp_damage)
    tick = ints(table, "tick")
    group_code = np.array([_HIT_GROUP_CODE.get(g, -1) for g in hit_group], dtype=np.int64)
    usable = np.zeros(len(table), dtype=bool)
    outcome_known = np.zeros(len(table), dtype=bool)
    for i in range(len(table)):
        if attacker[i] is None and weapon[i] in VOCABULARY:
            reason = "attacker not identifiable (no steamID or name)"
        elif attacker[i] is None or weapon[i] == "World":
            reason = "world damage (no attacker)"
        elif friendly[i] is True or (attacker_side[i] and attacker_side[i] == victim_side[i]):
            reason = "friendly fire"
        elif weapon_class[i] == "Grenade" or hit_group[i] == "Generic":
            reason = "grenade, fire or bomb"
        elif weapon[i] not in VOCABULARY:
            reason = "weapon outside the vocabulary"
        elif not (hp_taken[i] > 0 or hp_damage[i] > 0):
            reason = "no damage value"
        elif victim[i] is None:
            reason = "victim not identifiable (no steamID or name)"
        elif not np.isfinite(tick[i]):
            reason = "no tick"
        else:
            usable[i] = True
            outcome_known[i] = group_code[i] >= 0 and hp_damage[i] > 0
            if group_code[i] < 0:
                stats.partial["no hit group (scored on HP lost, over all hit groups)"] += 1
            elif not hp_damage[i] > 0:
                stats.partial["no raw damage (scored on HP lost)"] += 1
            continue
        stats.excluded[reason] += 1
    return DamageRows(
        tick=tick,
        attacker=attacker,
        victim=victim,
        weapon=weapon,
        hp_damage=hp_damage,
        hp_taken=np.nan_to_num(hp_taken),
        armor_damage=np.nan_to_num(ints(table, "armorDamage")),
        group_code=group_code,
        usable=usable,
        outcome_known=outcome_known,
    )


@dataclass(frozen=True)
class StepHit:
    """The hits of one pair in one step: the raw damage summed and capped at 100 (NaN when a hit
    lacks it), the hit group of the largest hit (-1 when a hit lacks one), the first row, the HP
    lost summed (capped by the victim's HP, as recorded) and the number of hits."""

    damage: float
    group: int
    first: int
    hp_lost: float
    hits: int


def aggregate(
    step: np.ndarray,
    attacker: np.ndarray,
    victim: np.ndarray,
    damages: DamageRows,
    rows: np.ndarray,
) -> dict[tuple[int, object, object], StepHit]:
    """Per (step, attacker, victim), over the damage rows `rows` (in row order): its `StepHit`.
    A step is known (a finite damage, a group) only when all its hits are `outcome_known`."""
    keyed: dict[tuple[int, object, object], list[int]] = {}
    for r in rows:
        keyed.setdefault((int(step[r]), attacker[r], victim[r]), []).append(int(r))
    out = {}
    for key, hits in keyed.items():
        raw = damages.hp_damage[hits]
        known = bool(damages.outcome_known[hits].all())
        largest = hits[int(np.argmax(raw))] if known else hits[0]
        out[key] = StepHit(
            damage=min(float(raw.sum()), MAX_DAMAGE_HP) if known else float("nan"),
            group=int(damages.group_code[largest]) if known else -1,
            first=hits[0],
            hp_lost=float(damages.hp_taken[hits].sum()),
            hits=len(hits),
        )
    return out


def step_clock(round_: Round) -> tuple[int, int]:
    """(origin tick, ticks per step) of the round's virtual 2 Hz steps, the simulator's combat
    step: a tick's step is rint((tick - origin) / ticks per step)."""
    origin = round_.start_tick if round_.start_tick is not None else 0
    return origin, max(1, round(round_.tick_rate / 2))


def group_id(round_: Round) -> str:
    """The split group of a round's samples: "MATCH rROUND"."""
    return f"{round_.match_id} r{round_.round_num}"
