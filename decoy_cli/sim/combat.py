"""The combat step: line of sight between enemy pairs, the damage-model interface, damage.

Every 0.5 s of game time (the engine decides when, by integer tick count) `CombatStep.run`:

1. `LineOfSight.visible_pairs` finds the ordered (attacker, victim) pairs of alive enemies whose
   eyes see each other, with one batched ray per unordered pair;
2. `make_batch` gathers everything a damage model needs about those pairs into a `CombatBatch`;
3. a `DamageModel` (DIP and DOG in `decoy_cli.damage`) says, per pair, whether the attacker hits
   and for how much and where;
4. `apply_damage` applies all damage of the step at once (two agents can kill each other) and
   returns the damage and kill events.

Line of sight, and what Bullet does with rays that start inside a body (measured, pybullet
3.2.7): a ray leaving a capsule from inside misses it when it points up or sideways, but reports
a hit at fraction 0 on that capsule when it points down. So the eye-to-eye test is split in two
ray batches:

* world rays, eye to eye, that see only the world mesh (`PhysicsWorld.line_of_sight`);
* for the pairs the world lets through, body rays that see only this module's capsules. They
  start 1 mm past the point where the segment leaves the first agent's own capsule (computed
  exactly: the eye lies on the capsule's axis) and end at the second agent's eye, inside its
  capsule. The first capsule hit is then the target's (clear) or another agent's (blocked);
  nothing hit is clear.

The capsules live in collision group `LOS_GROUP` with mask `WORLD_GROUP` (a ray's group is 1, so
a body is ray-tested only if its mask holds bit 1). The world's mask (WORLD_GROUP | AGENT_GROUP)
excludes LOS_GROUP, so they collide with nothing: `PhysicsWorld.capsules_blocked` and the
mover's capsules (AGENT_GROUP) never see them, and the rays here never see the mover's capsules.
Capsules of another `LineOfSight` in the same pybullet client are in the same group and do block.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Protocol

import numpy as np

from decoy_cli.csgo import EYE_HEIGHT_M, PLAYER_HEIGHT_M, PLAYER_RADIUS_M
from decoy_cli.sim.state import Agents, SimEvent
from decoy_cli.world.physics import WORLD_GROUP, PhysicsWorld

LOS_GROUP = 4
"""Collision group of the line-of-sight capsules: hit by this module's rays, touching nothing."""

HIT_GROUPS = ("Head", "Neck", "Chest", "Stomach", "Arm", "Leg")
"""Hit groups of the damage models, by code 0..5 (-1 = no hit)."""

NO_HIT = -1

_START_PAST_OWN_CAPSULE_M = 1e-3
_PARK_Z = -1e6


@dataclass(frozen=True)
class VisiblePairs:
    """K ordered (attacker, victim) agent index pairs, sorted by attacker then victim."""

    attacker: np.ndarray  # (K,) int64
    victim: np.ndarray  # (K,) int64

    def __len__(self) -> int:
        return len(self.attacker)


class LineOfSight:
    """Eye-to-eye visibility of alive enemies, blocked by the world and by other agents' bodies.

    Holds `count` upright capsules (radius and full height in metres, standing on the feet) in
    the physics client, one per agent; eyes are `eye_height` above the feet, inside the capsule.
    """

    def __init__(
        self,
        physics: PhysicsWorld,
        count: int,
        radius: float = PLAYER_RADIUS_M,
        height: float = PLAYER_HEIGHT_M,
        eye_height: float = EYE_HEIGHT_M,
    ) -> None:
        if count < 0:
            raise ValueError(f"cannot hold {count} agents")
        if not 0 < radius <= height / 2:
            raise ValueError(f"capsule radius {radius} m does not fit a height of {height} m")
        if not 0 < eye_height < height:
            raise ValueError(f"eye height {eye_height} m is not inside a {height} m body")
        self._p = physics._p
        self.physics = physics
        self.count = count
        self.radius = float(radius)
        self.height = float(height)
        self.eye_height = float(eye_height)
        p = self._p
        client = physics.client
        shape = p.createCollisionShape(
            p.GEOM_CAPSULE,
            radius=self.radius,
            height=max(self.height - 2 * self.radius, 1e-6),
            physicsClientId=client,
        )
        self.bodies: list[int] = []
        for k in range(count):
            body = p.createMultiBody(
                baseMass=0,
                baseCollisionShapeIndex=shape,
                basePosition=_park_position(k),
                physicsClientId=client,
            )
            p.setCollisionFilterGroupMask(body, -1, LOS_GROUP, WORLD_GROUP, physicsClientId=client)
            self.bodies.append(body)
        self._owner = {body: k for k, body in enumerate(self.bodies)}
        self._placed = np.full((count, 3), np.nan)  # feet each capsule stands on; NaN = parked

    def close(self) -> None:
        """Remove the capsules from the physics client (the client stays open)."""
        p = self._p
        client = self.physics.client
        if client is not None and p.isConnected(client):
            for body in self.bodies:
                p.removeBody(body, physicsClientId=client)
        self.bodies = []
        self._owner = {}

    def visible_pairs(self, agents: Agents) -> VisiblePairs:
        """All ordered (attacker, victim) pairs of alive agents of opposite sides that see each
        other, eye to eye; both orders of a visible pair are returned (visibility is symmetric).

        Blocked by the world and by the capsule of any other alive agent (either side); dead
        agents neither see nor block. Agents whose bodies overlap see each other.
        """
        if agents.count != self.count:
            raise ValueError(f"line of sight holds {self.count} agents, got {agents.count}")
        if len(self.bodies) != self.count:
            raise ValueError("line of sight is closed")
        alive = np.asarray(agents.alive, dtype=bool)
        t_side = np.flatnonzero(alive & (agents.side == "T"))
        ct_side = np.flatnonzero(alive & (agents.side == "CT"))
        if len(t_side) == 0 or len(ct_side) == 0:
            return _no_pairs()
        feet = np.asarray(agents.position, dtype=np.float64)
        if not np.all(np.isfinite(feet[alive])):
            raise ValueError("an alive agent has a NaN or infinite position")
        one, two = np.meshgrid(t_side, ct_side, indexing="ij")
        first = np.minimum(one, two).ravel()  # rays run from the lower to the higher index
        second = np.maximum(one, two).ravel()
        eyes = feet + np.array([0.0, 0.0, self.eye_height])
        clear = self.physics.line_of_sight(eyes[first], eyes[second])
        if np.any(clear) and np.count_nonzero(alive) > 2:
            self._place(feet, alive)
            ray = np.flatnonzero(clear)
            clear[ray] = self._bodies_clear(eyes, first[ray], second[ray])
        attacker = np.concatenate([first[clear], second[clear]])
        victim = np.concatenate([second[clear], first[clear]])
        order = np.lexsort((victim, attacker))
        return VisiblePairs(attacker[order].astype(np.int64), victim[order].astype(np.int64))

    def _place(self, feet: np.ndarray, alive: np.ndarray) -> None:
        """Stand the capsules of alive agents on their feet and park the others (only moves
        capsules whose place changed)."""
        p = self._p
        client = self.physics.client
        wanted = np.where(alive[:, None], feet, np.nan)
        same = np.all((wanted == self._placed) | (np.isnan(wanted) & np.isnan(self._placed)), 1)
        for k in np.flatnonzero(~same):
            if alive[k]:
                centre = [feet[k, 0], feet[k, 1], feet[k, 2] + self.height / 2]
            else:
                centre = _park_position(int(k))
            p.resetBasePositionAndOrientation(
                self.bodies[k], centre, [0.0, 0.0, 0.0, 1.0], physicsClientId=client
            )
        self._placed = wanted

    def _bodies_clear(self, eyes: np.ndarray, first: np.ndarray, second: np.ndarray) -> np.ndarray:
        """True where no capsule but the two agents' own lies between their eyes."""
        segment = eyes[second] - eyes[first]
        length = np.linalg.norm(segment, axis=1)
        t = _capsule_exit(segment, self.eye_height, self.radius, self.height)
        t = t + _START_PAST_OWN_CAPSULE_M / np.where(length > 0, length, 1.0)
        clear = np.ones(len(first), dtype=bool)
        cast = np.flatnonzero((t < 1.0) & (length > 0))  # else the eyes share one body: clear
        starts = eyes[first[cast]] + t[cast, None] * segment[cast]
        ends = eyes[second[cast]]
        hits = self.physics.cast_rays(starts, ends, LOS_GROUP)
        hit = np.fromiter((self._owner.get(h[0], -2) if h[0] >= 0 else -1 for h in hits), int)
        clear[cast] = (hit == -1) | (hit == second[cast])
        return clear


def _park_position(k: int) -> list[float]:
    """Where capsule k waits while its agent is dead: far below the map, apart from the others."""
    return [0.0, 0.0, _PARK_Z - 10.0 * k]


def _no_pairs() -> VisiblePairs:
    return VisiblePairs(np.zeros(0, np.int64), np.zeros(0, np.int64))


def _capsule_exit(segment: np.ndarray, eye: float, radius: float, height: float) -> np.ndarray:
    """(K,) parameter t along each segment (eye + t * segment) where it leaves the upright
    capsule its eye stands in; the eye lies on the axis, `eye` above the capsule's bottom.

    The capsule is the union of a cylinder and two spheres; a segment starting inside a convex
    union leaves it at the largest exit parameter of its parts. Zero-length segments give 0.
    """
    dz = segment[:, 2]
    horizontal = np.hypot(segment[:, 0], segment[:, 1])
    length2 = np.einsum("ij,ij->i", segment, segment)
    low, high = radius, height - radius  # axis ends (sphere centres) above the bottom
    exit_t = np.zeros(len(segment))
    with np.errstate(divide="ignore", invalid="ignore"):
        for centre in (low, high):
            b = (eye - centre) * dz
            c = (eye - centre) ** 2 - radius**2
            disc = b * b - length2 * c
            root = (-b + np.sqrt(np.maximum(disc, 0.0))) / length2
            exit_t = np.maximum(exit_t, np.where((disc >= 0) & (length2 > 0), root, 0.0))
        side = np.where(horizontal > 0, radius / horizontal, np.inf)
        enter_slab = np.where(dz > 0, (low - eye) / dz, (high - eye) / dz)
        leave_slab = np.where(dz > 0, (high - eye) / dz, (low - eye) / dz)
        flat = dz == 0
        in_slab = low <= eye <= high
        enter_slab = np.where(flat, -np.inf if in_slab else np.inf, enter_slab)
        leave_slab = np.where(flat, np.inf if in_slab else -np.inf, leave_slab)
        leave = np.minimum(side, leave_slab)
        cylinder = (leave >= np.maximum(enter_slab, 0.0)) & np.isfinite(leave)
        exit_t = np.maximum(exit_t, np.where(cylinder, leave, 0.0))
    return exit_t


# ---- the damage-model interface ---------------------------------------------------------------


@dataclass(frozen=True)
class CombatBatch:
    """What a damage model sees of K visible ordered (attacker, victim) pairs.

    Positions are the feet in metres; yaws are degrees (0 = +x, counter-clockwise). `distance`
    is the 3-D distance between the feet. `bearing` is the horizontal direction of the victim
    seen from the attacker, relative to the attacker's view yaw, radians in [-pi, pi): 0 straight
    ahead, positive to the attacker's left (counter-clockwise), negative to the right; 0 for a
    victim straight above or below.
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
    distance: np.ndarray  # (K,) float64 metres
    bearing: np.ndarray  # (K,) float64 radians
    map_name: str

    def __len__(self) -> int:
        return len(self.attacker)


def make_batch(agents: Agents, pairs: VisiblePairs, map_name: str) -> CombatBatch:
    """Gather the state of both agents of every pair (copies: later state changes do not leak)."""
    a = np.asarray(pairs.attacker, dtype=np.int64)
    v = np.asarray(pairs.victim, dtype=np.int64)
    if a.shape != v.shape or a.ndim != 1:
        raise ValueError("attacker and victim indices must be 1-D arrays of the same length")
    if len(a) and (min(a.min(), v.min()) < 0 or max(a.max(), v.max()) >= agents.count):
        raise ValueError(f"pair indices outside 0..{agents.count - 1}")
    position = np.asarray(agents.position, dtype=np.float64)
    yaw = np.asarray(agents.yaw, dtype=np.float64)
    delta = position[v] - position[a]
    ahead = np.arctan2(delta[:, 1], delta[:, 0]) - np.radians(yaw[a])
    bearing = np.where(np.hypot(delta[:, 0], delta[:, 1]) > 0, _wrap(ahead), 0.0)
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
        distance=np.linalg.norm(delta, axis=1),
        bearing=bearing,
        map_name=map_name,
    )


def _wrap(angle: np.ndarray) -> np.ndarray:
    """Angles in radians wrapped to [-pi, pi)."""
    return (angle + np.pi) % (2 * np.pi) - np.pi


@dataclass(frozen=True)
class DamageResult:
    """A damage model's answer for K pairs: whether the attacker hits, the HP it removes from
    the victim (after armor; 0 for a miss) and the hit group code (0..5, HIT_GROUPS; -1 for a
    miss). Checked on construction: a model that returns garbage fails loudly."""

    damage: np.ndarray  # (K,) int64, >= 0
    hit_group: np.ndarray  # (K,) int8, -1..5
    hit: np.ndarray  # (K,) bool

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
        object.__setattr__(self, "damage", damage.astype(np.int64))
        object.__setattr__(self, "hit_group", group.astype(np.int8))
        object.__setattr__(self, "hit", hit)

    def __len__(self) -> int:
        return len(self.damage)


class DamageModel(Protocol):
    """Decides the outcome of every visible pair of one combat step in one batched call."""

    def __call__(self, batch: CombatBatch, rng: np.random.Generator) -> DamageResult: ...


# ---- applying damage --------------------------------------------------------------------------


def apply_damage(
    agents: Agents, batch: CombatBatch, result: DamageResult, tick: int
) -> list[SimEvent]:
    """Apply all damage of one combat step at once and return its events.

    Each victim loses the sum of the damage of all its attackers (HP stays an integer, clipped
    at 0); a victim at 0 HP dies. Every attacker fires on the state before the step, so two
    agents can kill each other. Armor is not worn down (the models give HP damage after armor).

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
    hp_after = np.maximum(agents.hp.astype(np.int64) - total, 0)
    died = np.flatnonzero(agents.alive & (total > 0) & (hp_after == 0))
    agents.hp[:] = hp_after.astype(agents.hp.dtype)
    agents.alive[died] = False
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
    """One combat step: line of sight, the damage model on the visible pairs, damage applied."""

    def __init__(self, los: LineOfSight, model: DamageModel, map_name: str) -> None:
        self.los = los
        self.model = model
        self.map_name = map_name

    def run(self, agents: Agents, tick: int, rng: np.random.Generator) -> list[SimEvent]:
        """Run the step on the agents (changed in place); the model is not called when no
        pair is visible."""
        pairs = self.los.visible_pairs(agents)
        if len(pairs) == 0:
            return []
        batch = make_batch(agents, pairs, self.map_name)
        return apply_damage(agents, batch, self.model(batch, rng), tick)
