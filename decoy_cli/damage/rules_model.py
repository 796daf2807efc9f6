"""`RulesDamage`: the simulator's damage model grounded in the game's rules (issue 13).

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
`rules.json` beside the DIP (`decoy models fit-rules`). Only an attacker with a firearm of the
models' vocabulary hits (`DipDecision`), as with the learned DOG; the rule table covers exactly
that vocabulary (a test checks), so a knife, grenade, Zeus or C4 never hits here.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from decoy_cli.csgo import HAMMER_TO_M
from decoy_cli.damage.bullet_counts import ALL, BulletCounts
from decoy_cli.damage.hit_groups import GROUPS, HitGroupModel, group_posterior
from decoy_cli.damage.rules import rule_group, shot_damage
from decoy_cli.errors import ModelError
from decoy_cli.esta import Round
from decoy_cli.files import write_json
from decoy_cli.reading import load_json
from decoy_cli.sim.combat import NO_HIT, CombatBatch, DamageResult

if TYPE_CHECKING:
    from decoy_cli.damage.damage_rows import DamageRows
    from decoy_cli.damage.model_folder import LoadedDip

RULES_FILE = "rules.json"
FULL_HP = 100
"""A victim at this HP at a step's start is unhurt (`RulesFile.bullets`)."""


PENETRATED_BELOW = 0.9
"""A real hit whose health damage is below this share of the least the rules give at its range
and hit group (armour and helmet on) went through something first (measured on the real hits:
`benchmarks/damage_rules_check.py` finds the rules exact on nearly all others)."""


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


def fit_rules(rounds: Sequence[Round]) -> RulesFile:
    """Learn the hit groups, the penetration and the bullets per step from the rounds' firearm
    hits: the damage rows the DOG's samples use (`damage_rows`). Bullets are counted per
    (attacker, victim) and virtual 2 Hz step exactly as the events mode aggregates them, so a
    step here is a sample's step, from every hit (also those whose data records only the HP
    lost); hit groups and penetration from the hits whose raw damage and hit group are known."""
    from decoy_cli.damage.damage_rows import aggregate, damage_rows, step_clock
    from decoy_cli.damage.sample_set import SampleStats

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


def rules_generate(
    rules: RulesFile,
    weapons: Sequence[str],
    distances_m: np.ndarray,
    armor: np.ndarray,
    helmet: np.ndarray,
    victim_hp: np.ndarray,
    seed: int,
    draws: int,
) -> tuple[np.ndarray, np.ndarray]:
    """`draws` outcomes of K damaging pair-steps (victims with `victim_hp` at its start), as
    the DOG's generative mode gives them:
    (draws, K) damage in HP (summed, in [1, 100]) and hit-group codes. A weapon the rules lack
    raises `UnknownWeaponError`."""
    draw = np.random.default_rng(seed)
    damage = np.zeros((draws, len(weapons)))
    group = np.zeros((draws, len(weapons)), dtype=np.int64)
    for d in range(draws):
        for k, weapon in enumerate(weapons):
            health, _, name = pair_outcome(
                rules,
                weapon,
                float(distances_m[k]) / HAMMER_TO_M,
                int(armor[k]),
                bool(helmet[k]),
                draw,
                int(victim_hp[k]),
            )
            damage[d, k] = min(max(health, 1), 100)
            group[d, k] = GROUPS.index(name)
    return damage, group


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
