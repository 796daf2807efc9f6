"""`RulesDamage`: the simulator's damage model grounded in the game's rules.

Per combat step, over every visible ordered pair at once:

1. DIP decides which attackers hit their victim in this 0.5 s step (`DipDecision`: its threshold,
   or its calibration's rule);
2. for each hitting pair, the number of bullets that land in the step is drawn from a
   distribution learned from real steps by weapon and range, apart for victims unhurt and hurt
   (`bullet_counts.BulletCounts`), each bullet's hit group from `HitGroupModel` (weapon and
   distance), and each bullet's health and armour damage from
   the rules (decoy_cli/damage/rules.py) against the victim's armour and helmet, the armour worn
   down bullet by bullet, and a learned share of bullets scaled down as through a wall
   (`Penetration`);
3. the pair's damage is the bullets' health damage summed, at least 1 and at most the victim's
   HP (as ESTA's hpDamageTaken), its armour damage the armour they took, its hit group that of
   the bullet that did the most.

The learned parts (`RulesFile`: hit groups, bullet counts, penetration) live in a model folder's
`rules.json` beside the DIP (`decoy models fit-rules`: decoy_cli/modeling/rules_fit.py). Only an
attacker with a firearm of the models' vocabulary hits (`DipDecision`), as with the learned DOG;
the rule table covers exactly that vocabulary (a test checks), so a knife, grenade, Zeus or C4
never hits here.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from decoy_cli.csgo import HAMMER_TO_M
from decoy_cli.damage.bullet_counts import BulletCounts
from decoy_cli.damage.hit_groups import GROUPS, HitGroupModel
from decoy_cli.damage.rules import rule_group, shot_damage
from decoy_cli.errors import ModelError
from decoy_cli.files import write_json
from decoy_cli.reading import load_json
from decoy_cli.sim.combat import NO_HIT, CombatBatch, DamageResult

if TYPE_CHECKING:
    from decoy_cli.damage.model_folder import LoadedDip

RULES_FILE = "rules.json"
FULL_HP = 100
"""A victim at this HP at a step's start is unhurt (`RulesFile.bullets`)."""


PENETRATED_BELOW = 0.9
"""A real hit whose health damage is below this share of the least the rules give at its range
and hit group (armour and helmet on) went through something first (measured on the real hits:
`benchmarks/studies/damage_rules_check.py` finds the rules exact on nearly all others)."""


@dataclass
class Penetration:
    """Bullets that pass through a wall, a box or a player before they land do less damage
    (CS:GO's penetration), and the world has no materials to say when. Learned from real hits:
    the share of hits that did less than the rules allow (`PENETRATED_BELOW`) and what share of
    the rules' damage each of them did; a drawn bullet is such a hit with that share, its damage
    scaled by one of those shares."""

    hits: int = 0
    shares: list[float] = field(default_factory=list)

    @classmethod
    def learn(
        cls,
        weapons: Sequence[str],
        groups: Sequence[str],
        distances_u: Sequence[float],
        health: Sequence[float],
    ) -> Penetration:
        """From real hits: weapon, ESTA hit group, distance (u) and raw health damage."""
        found = cls()
        for weapon, group, distance, done in zip(weapons, groups, distances_u, health, strict=True):
            least = shot_damage(weapon, rule_group(group), distance, armor=100, helmet=True).health
            found.hits += 1
            if least > 0 and done < PENETRATED_BELOW * least:
                found.shares.append(float(done) / least)
        return found

    def factor(self, draw: np.random.Generator) -> float:
        """1.0 for a bullet with a clear path, else the share of its damage a penetrating one
        does; two draws either way, so the stream does not depend on the outcome."""
        through, pick = draw.random(), draw.random()
        if not self.shares or through >= len(self.shares) / self.hits:
            return 1.0
        return self.shares[int(pick * len(self.shares))]


@dataclass
class RulesFile:
    """The learned parts of the rules-grounded model (a model folder's `rules.json`)."""

    hit_groups: HitGroupModel
    bullets: BulletCounts
    provenance: dict[str, object] = field(default_factory=dict)
    penetration: Penetration = field(default_factory=Penetration)
    """Empty in a `rules.json` written before it was learned: every path is clear."""
    bullets_hurt: BulletCounts | None = None
    """The bullets of steps on a victim already hurt (below 100 HP at the step's start), and
    `bullets` those on a victim unhurt; None in a `rules.json` written before: `bullets`."""

    def bullet_counts(self, victim_hp: int) -> BulletCounts:
        """The bullet counts of a step on a victim with `victim_hp` at its start."""
        hurt = victim_hp < FULL_HP and self.bullets_hurt is not None
        return self.bullets_hurt if hurt and self.bullets_hurt is not None else self.bullets

    def save(self, folder: Path) -> Path:
        """Write `rules.json` into the folder (atomically, as every JSON file of the project)."""
        data = {
            "hit_groups": self.hit_groups.to_dict(),
            "bullets": self.bullets.to_dict(),
            "bullets_hurt": None if self.bullets_hurt is None else self.bullets_hurt.to_dict(),
            "penetration": {"hits": self.penetration.hits, "shares": self.penetration.shares},
            "provenance": self.provenance,
        }
        return write_json(Path(folder) / RULES_FILE, data)

    @classmethod
    def load(cls, folder: Path) -> RulesFile:
        """The folder's `rules.json`; a missing or unreadable one is one ModelError line."""
        path = Path(folder) / RULES_FILE
        document = load_json(path, ModelError)
        if not isinstance(document, dict):
            raise ModelError(f"{path}: not a rules file (not a JSON object)")
        data: dict[str, Any] = document
        try:
            hit_groups = HitGroupModel.from_dict(data["hit_groups"])
            bullets = BulletCounts.from_dict(data["bullets"])
            hurt = data.get("bullets_hurt")
            bullets_hurt = None if hurt is None else BulletCounts.from_dict(hurt)
            bullets.check("bullets")
            if bullets_hurt is not None:
                bullets_hurt.check("bullets_hurt")
            provenance = dict(data.get("provenance", {}))
            through = data.get("penetration", {"hits": 0, "shares": []})
            penetration = Penetration(int(through["hits"]), [float(v) for v in through["shares"]])
        except (ValueError, KeyError, TypeError, AttributeError, OverflowError) as error:
            raise ModelError(f"{path}: not a rules file ({error})") from None
        if not (0 <= len(penetration.shares) <= penetration.hits) or not all(
            0.0 <= v <= 1.0 for v in penetration.shares
        ):
            raise ModelError(f"{path}: penetration shares must be in [0, 1], at most one per hit")
        return cls(hit_groups, bullets, provenance, penetration, bullets_hurt)


def pair_outcome(
    rules: RulesFile,
    weapon: str,
    distance_u: float,
    armor: int,
    helmet: bool,
    draw: np.random.Generator,
    victim_hp: int = FULL_HP,
) -> tuple[int, int, str]:
    """One damaging step of one pair (module doc, step 2) on a victim with `victim_hp` at the
    step's start: (health damage summed over the bullets, armour they took, the hit group of
    the bullet that did the most)."""
    p = rules.bullet_counts(victim_hp).probabilities(weapon, distance_u)
    count = 1 + int(np.searchsorted(np.cumsum(p), draw.random() * p.sum()))
    groups = rules.hit_groups.sample(draw, [weapon] * count, [distance_u] * count)
    health, taken, largest, largest_group = 0, 0, -1, groups[0]
    for name in groups:
        bullet = shot_damage(weapon, name, distance_u, armor=armor - taken, helmet=helmet)
        factor = rules.penetration.factor(draw)
        done = int(bullet.health * factor)
        health += done
        taken += int(bullet.armor * factor)
        if done > largest:
            largest, largest_group = done, name
    return health, taken, largest_group


class RulesDamage:
    """A `DamageModel`: DIP decides who hits, the rules how much and where (module doc)."""

    def __init__(
        self,
        dip: LoadedDip,
        rules: RulesFile,
        threshold: float | None = None,
        threads: int | None = 1,
    ) -> None:
        from decoy_cli.damage.combat import DipDecision

        self.decision = DipDecision(dip, threshold, threads)
        self.dip = dip
        self.rules = rules

    def __call__(self, batch: CombatBatch, rng: np.random.Generator) -> DamageResult:
        from decoy_cli.damage.features import encode

        k = len(batch)
        seed = int(rng.integers(2**63))  # drawn every call: the stream does not depend on hits
        damage = np.zeros(k, dtype=np.int64)
        armor_damage = np.zeros(k, dtype=np.int64)
        group = np.full(k, NO_HIT, dtype=np.int8)
        if k == 0:
            return DamageResult(damage, group, np.zeros(0, dtype=bool), armor_damage)
        # two independent streams: the hit decisions' and the outcomes'
        decide_seed, outcome_seed = np.random.SeedSequence(seed).spawn(2)
        decision = self.decision
        hit = decision.hits(batch, encode(batch, decision.dip.spec), decide_seed)
        draw = np.random.default_rng(outcome_seed)
        for row in np.flatnonzero(hit):
            health, taken, name = pair_outcome(
                self.rules,
                str(batch.attacker_weapon[row]),
                float(batch.distance[row]) / HAMMER_TO_M,
                int(batch.victim_armor[row]),
                bool(batch.victim_helmet[row]),
                draw,
                int(batch.victim_hp[row]),
            )
            damage[row] = min(max(health, 1), max(int(batch.victim_hp[row]), 1))
            armor_damage[row] = taken
            group[row] = GROUPS.index(name)
        return DamageResult(damage, group, hit, armor_damage)
