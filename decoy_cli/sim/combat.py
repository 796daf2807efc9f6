"""The combat step: line of sight between enemy pairs, the damage-model interface, damage.

Every 0.5 s of game time (the engine decides when, by integer tick count) `CombatStep.run`:

1. `LineOfSight.visible_pairs` finds the ordered (attacker, victim) pairs of alive enemies whose
   eyes see each other, with one batched ray per unordered pair;
2. `aimed_yaw` turns each agent who has had an enemy in sight for a reaction time toward the
   nearest such enemy (`REACTION_S`), and `make_batch` gathers everything a damage model needs
   about the pairs, with those view yaws, into a `CombatBatch`;
3. a `DamageModel` (DIP and DOG in `decoy_cli.damage`) says, per pair, whether the attacker hits
   and for how much and where;
4. `apply_damage` applies all damage of the step at once (two agents can kill each other) and
   returns the damage and kill events.

Line of sight (`LineOfSight`, `VisiblePairs`) lives in `decoy_cli.sim.sight` and is importable
from here too.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from functools import cached_property
from typing import Protocol

import numpy as np

from decoy_cli.csgo import seconds_to_ticks
from decoy_cli.geometry import eye_point, facing_yaw
from decoy_cli.sim.sight import LOS_GROUP, LineOfSight, VisiblePairs
from decoy_cli.sim.state import Agents, SimEvent
from decoy_cli.sim.utility import FIRE_HP_PER_S, Utility

__all__ = [
    "HIT_GROUPS",
    "LOS_GROUP",
    "NO_HIT",
    "PAIR_FIELDS",
    "REACTION_S",
    "CombatBatch",
    "CombatStep",
    "DamageModel",
    "DamageResult",
    "LineOfSight",
    "VisiblePairs",
    "aimed_yaw",
    "apply_damage",
    "make_batch",
]

HIT_GROUPS = ("Head", "Neck", "Chest", "Stomach", "Arm", "Leg")
"""Hit groups of the damage models, by code 0..5 (-1 = no hit)."""

NO_HIT = -1

REACTION_S = 0.25
"""How long an agent has an enemy in sight before he aims at him: a human's visual reaction
time, about a quarter of a second (chosen from that; `benchmarks/studies/aim_study.py` measures
how long real pairs were in sight before the first damage, README). Until then he
looks where he was going, as the movers turn him. Sight is tested at combat steps only, so at
the paper's cadence (0.5 s) he aims from the second step in a row that finds the enemy in sight.
The damage models learned from real shots, taken by players aiming at their victims: a replay
whose agents never aim hits far less."""


# ---- the damage-model interface ---------------------------------------------------------------


@dataclass(frozen=True)
class CombatBatch:
    """What a damage model sees of K visible ordered (attacker, victim) pairs.

    Positions are the feet in metres; yaws are degrees (0 = +x, counter-clockwise). It holds
    the pairs' state only (`PAIR_FIELDS`, with the indices and the map): `distance` is derived
    from it, `concat` joins batches, and a damage model that wants bearings computes them from
    the positions and yaws (`decoy_cli.geometry.bearing`).
    """

    attacker: np.ndarray  # (K,) int64 agent index
    victim: np.ndarray  # (K,) int64 agent index
    attacker_position: np.ndarray  # (K, 3) float64
    victim_position: np.ndarray  # (K, 3) float64
    attacker_yaw: np.ndarray  # (K,) float64 degrees
    victim_yaw: np.ndarray  # (K,) float64 degrees
    attacker_hp: np.ndarray  # (K,) int16
    victim_hp: np.ndarray  # (K,) int16
    attacker_weapon: np.ndarray  # (K,) str (awpy display names)
    victim_armor: np.ndarray  # (K,) int16
    victim_helmet: np.ndarray  # (K,) bool
    map_name: str

    def __len__(self) -> int:
        return len(self.attacker)

    @cached_property
    def distance(self) -> np.ndarray:
        """(K,) float64 the 3-D distance between the feet, metres."""
        victim = np.asarray(self.victim_position, dtype=np.float64)
        return np.linalg.norm(victim - np.asarray(self.attacker_position, dtype=np.float64), axis=1)

    @staticmethod
    def concat(parts: Sequence[CombatBatch]) -> CombatBatch:
        """The pairs of all the batches, in order (one map: theirs)."""
        maps = {part.map_name for part in parts}
        if len(maps) != 1:
            raise ValueError(f"batches of one map are joined, got maps {sorted(maps)}")
        return CombatBatch(
            **{
                name: np.concatenate([getattr(part, name) for part in parts])
                for name in ("attacker", "victim", *PAIR_FIELDS)
            },
            map_name=maps.pop(),
        )


PAIR_FIELDS = tuple(
    name
    for name in CombatBatch.__dataclass_fields__
    if name not in ("attacker", "victim", "map_name")
)
"""The state of each pair a `CombatBatch` holds: its attacker's and victim's positions, yaws,
HP, the attacker's weapon, the victim's armour and helmet (one array each)."""


def make_batch(
    agents: Agents, pairs: VisiblePairs, map_name: str, yaw: np.ndarray | None = None
) -> CombatBatch:
    """Gather the state of both agents of every pair (copies: later state changes do not leak);
    `yaw` (N,) the agents' view yaws in degrees (`aimed_yaw`; default: `agents.yaw`)."""
    a = np.asarray(pairs.attacker, dtype=np.int64)
    v = np.asarray(pairs.victim, dtype=np.int64)
    if a.shape != v.shape or a.ndim != 1:
        raise ValueError("attacker and victim indices must be 1-D arrays of the same length")
    if len(a) and (min(a.min(), v.min()) < 0 or max(a.max(), v.max()) >= agents.count):
        raise ValueError(f"pair indices outside 0..{agents.count - 1}")
    position = np.asarray(agents.position, dtype=np.float64)
    yaw = np.asarray(agents.yaw if yaw is None else yaw, dtype=np.float64)
    return CombatBatch(
        attacker=a,
        victim=v,
        attacker_position=position[a],
        victim_position=position[v],
        attacker_yaw=yaw[a],
        victim_yaw=yaw[v],
        attacker_hp=np.asarray(agents.hp)[a],
        victim_hp=np.asarray(agents.hp)[v],
        attacker_weapon=np.asarray(agents.weapon)[a],
        victim_armor=np.asarray(agents.armor)[v],
        victim_helmet=np.asarray(agents.helmet, dtype=bool)[v],
        map_name=map_name,
    )


def aimed_yaw(agents: Agents, pairs: VisiblePairs, aims: np.ndarray) -> np.ndarray:
    """(N,) view yaws in degrees: an agent toward the nearest victim of the pairs where `aims`
    is True (the pairs he has had in sight long enough to aim), else his own yaw."""
    yaw = np.asarray(agents.yaw, dtype=np.float64).copy()
    attacker, victim = pairs.attacker[aims], pairs.victim[aims]
    if len(attacker) == 0:
        return yaw
    position = np.asarray(agents.position, dtype=np.float64)
    delta = position[victim, :2] - position[attacker, :2]
    order = np.lexsort((np.hypot(delta[:, 0], delta[:, 1]), attacker))  # nearest first
    nearest = order[np.r_[True, attacker[order][1:] != attacker[order][:-1]]]
    yaw[attacker[nearest]] = facing_yaw(delta[nearest, 0], delta[nearest, 1])
    return yaw


@dataclass(frozen=True)
class DamageResult:
    """A damage model's answer for K pairs: whether the attacker hits, the HP it removes from
    the victim (after armor; 0 for a miss), the hit group code (0..5, HIT_GROUPS; -1 for a
    miss) and the armor it removes (None: none, as a model of HP damage after armor says).
    Checked on construction: a model that returns garbage fails loudly."""

    damage: np.ndarray  # (K,) int64, >= 0
    hit_group: np.ndarray  # (K,) int8, -1..5
    hit: np.ndarray  # (K,) bool
    armor_damage: np.ndarray | None = None  # (K,) int64, >= 0, 0 for a miss

    def __post_init__(self) -> None:
        damage, group, hit = (np.asarray(x) for x in (self.damage, self.hit_group, self.hit))
        if damage.ndim != 1 or damage.shape != group.shape or damage.shape != hit.shape:
            raise ValueError("damage, hit_group and hit must be 1-D arrays of one length")
        if not np.issubdtype(damage.dtype, np.integer):
            raise ValueError(f"damage must be integers, got {damage.dtype}")
        if not np.issubdtype(group.dtype, np.integer):
            raise ValueError(f"hit_group must be integers, got {group.dtype}")
        if hit.dtype != bool:
            raise ValueError(f"hit must be booleans, got {hit.dtype}")
        if np.any(damage < 0):
            raise ValueError("damage must not be negative")
        if np.any(damage[~hit] != 0) or np.any(group[~hit] != NO_HIT):
            raise ValueError("a miss must have damage 0 and hit group -1")
        if np.any((group[hit] < 0) | (group[hit] >= len(HIT_GROUPS))):
            raise ValueError(f"a hit needs a hit group in 0..{len(HIT_GROUPS) - 1}")
        armor = (
            np.zeros_like(damage) if self.armor_damage is None else np.asarray(self.armor_damage)
        )
        if armor.shape != damage.shape or not np.issubdtype(armor.dtype, np.integer):
            raise ValueError("armor_damage must be integers, one per pair")
        if np.any(armor < 0) or np.any(armor[~hit] != 0):
            raise ValueError("armor_damage must not be negative, and 0 for a miss")
        object.__setattr__(self, "damage", damage.astype(np.int64))
        object.__setattr__(self, "hit_group", group.astype(np.int8))
        object.__setattr__(self, "hit", hit)
        object.__setattr__(self, "armor_damage", armor.astype(np.int64))

    def __len__(self) -> int:
        return len(self.damage)


class DamageModel(Protocol):
    """Decides the outcome of every visible pair of one combat step in one batched call."""

    def __call__(self, batch: CombatBatch, rng: np.random.Generator) -> DamageResult: ...


# ---- applying damage --------------------------------------------------------------------------


def apply_damage(
    agents: Agents, batch: CombatBatch, result: DamageResult, tick: int, *, kills: bool = True
) -> list[SimEvent]:
    """Apply all damage of one combat step at once and return its events.

    Each victim loses the sum of the damage of all its attackers (HP stays an integer, clipped
    at 0); a victim at 0 HP dies. With `kills` False nobody dies: HP stops at 1 (a replay whose
    deaths follow the data, `--deaths data`). Every attacker fires on the state before the
    step, so two agents can kill each other. Armor goes down by the result's armor damage
    (clipped at 0; the learned DIP + DOG give none: their damage is HP after armor).

    Events, in this order: "damage" per hit pair in batch order (agent = attacker, other =
    victim; data: damage, hit_group, weapon, hp_after = the victim's HP after the whole step),
    then "kill" per victim that died, by victim index (agent = the credited attacker, other =
    victim; data: weapon, hit_group). The kill goes to the attacker that dealt that victim the
    most damage in this step; ties go to the lowest attacker index.
    """
    if len(result) != len(batch):
        raise ValueError(f"a damage result for {len(result)} pairs, batch of {len(batch)}")
    if len(batch) == 0:
        return []
    if not (np.all(agents.alive[batch.attacker]) and np.all(agents.alive[batch.victim])):
        raise ValueError("the batch names a dead agent: build it from the current state")
    hit = result.hit
    damage = result.damage
    total = np.zeros(agents.count, dtype=np.int64)
    np.add.at(total, batch.victim, damage)
    hp_after = np.maximum(agents.hp.astype(np.int64) - total, 0 if kills else 1)
    died = np.flatnonzero(agents.alive & (total > 0) & (hp_after == 0))
    agents.hp[:] = hp_after.astype(agents.hp.dtype)
    agents.alive[died] = False
    armor_lost = np.zeros(agents.count, dtype=np.int64)
    assert result.armor_damage is not None  # filled in on construction
    np.add.at(armor_lost, batch.victim, result.armor_damage)
    agents.armor[:] = np.maximum(agents.armor.astype(np.int64) - armor_lost, 0).astype(
        agents.armor.dtype
    )
    events = [
        SimEvent(
            tick,
            "damage",
            int(batch.attacker[k]),
            int(batch.victim[k]),
            {
                "damage": int(damage[k]),
                "hit_group": int(result.hit_group[k]),
                "weapon": str(batch.attacker_weapon[k]),
                "hp_after": int(hp_after[batch.victim[k]]),
            },
        )
        for k in np.flatnonzero(hit)
    ]
    for victim in died:
        rows = np.flatnonzero(hit & (batch.victim == victim))
        best = rows[np.lexsort((batch.attacker[rows], -damage[rows]))[0]]
        events.append(
            SimEvent(
                tick,
                "kill",
                int(batch.attacker[best]),
                int(victim),
                {
                    "weapon": str(batch.attacker_weapon[best]),
                    "hit_group": int(result.hit_group[best]),
                },
            )
        )
    return events


class CombatStep:
    """One combat step: line of sight, aim, the damage model on the visible pairs, damage
    applied. Remembers since when each pair has been in sight at every step (one round)."""

    def __init__(
        self,
        los: LineOfSight,
        model: DamageModel,
        map_name: str,
        *,
        kills: bool = True,
        utility: Utility | None = None,
        step_s: float = 0.5,
    ) -> None:
        self.los = los
        self.model = model
        self.map_name = map_name
        self.kills = kills
        self.utility = utility
        """The data's smokes, fires and blinds (decoy_cli/sim/utility.py); None: none."""
        self.fire_hp = round(FIRE_HP_PER_S * step_s)
        """HP a fire takes from a player in it at each step (`step_s` apart)."""
        self._in_sight_since = np.full((los.count, los.count), -1, dtype=np.int64)
        self._reaction_ticks = seconds_to_ticks(REACTION_S)

    def run(self, agents: Agents, tick: int, rng: np.random.Generator) -> list[SimEvent]:
        """Run the step on the agents (changed in place); the model is not called when no
        pair is visible."""
        pairs = self.los.visible_pairs(agents)
        if self.utility is not None:
            pairs = self._through_utility(agents, pairs, tick)
        since = self._in_sight_since
        if len(pairs) == 0:
            since.fill(-1)
            return self._burn(agents, tick)
        seen_before = since[pairs.attacker, pairs.victim]
        since.fill(-1)
        seen = np.where(seen_before >= 0, seen_before, tick)
        since[pairs.attacker, pairs.victim] = seen
        aims = seen <= tick - self._reaction_ticks
        yaw = aimed_yaw(agents, pairs, aims)
        batch = make_batch(agents, pairs, self.map_name, yaw)
        events = apply_damage(agents, batch, self.model(batch, rng), tick, kills=self.kills)
        return events + self._burn(agents, tick)

    def _through_utility(self, agents: Agents, pairs: VisiblePairs, tick: int) -> VisiblePairs:
        """The pairs smoke does not hide, less those whose attacker is blind (he does not
        shoot; a blind victim is still seen)."""
        assert self.utility is not None
        eyes = eye_point(np.asarray(agents.position, dtype=np.float64), self.los.eye_height)
        keep = ~self.utility.sight_blocked(eyes[pairs.attacker], eyes[pairs.victim], tick)
        keep &= ~self.utility.blinded(agents.count, tick)[pairs.attacker]
        return VisiblePairs(pairs.attacker[keep], pairs.victim[keep])

    def _burn(self, agents: Agents, tick: int) -> list[SimEvent]:
        """Fire damage to the alive agents standing in an active fire; one it brings to 0 HP
        dies (unless nothing kills: then it stops at 1)."""
        if self.utility is None:
            return []
        feet = np.asarray(agents.position, dtype=np.float64)
        burning = np.flatnonzero(self.utility.burning(feet, tick) & agents.alive)
        events = []
        for agent in burning.tolist():
            left = max(0 if self.kills else 1, int(agents.hp[agent]) - self.fire_hp)
            taken = int(agents.hp[agent]) - left
            agents.hp[agent] = left
            events.append(SimEvent(tick, "fire_damage", agent, data={"damage": taken}))
            if left == 0:
                agents.alive[agent] = False
                events.append(SimEvent(tick, "death", agent, data={"reason": "fire"}))
        return events
