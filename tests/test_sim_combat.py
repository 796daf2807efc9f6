"""The combat step: line of sight in hand-made worlds, the combat batch, simultaneous damage."""

from __future__ import annotations

from collections.abc import Iterator

import numpy as np
import pybullet
import pytest
from worlds import box, floor, wall

from decoy_cli.csgo import EYE_HEIGHT_M, PLAYER_HEIGHT_M, PLAYER_RADIUS_M, TICK_RATE
from decoy_cli.geometry import bearing
from decoy_cli.sim.combat import (
    HIT_GROUPS,
    PAIR_FIELDS,
    REACTION_S,
    CombatBatch,
    CombatStep,
    DamageResult,
    LineOfSight,
    VisiblePairs,
    aimed_yaw,
    apply_damage,
    make_batch,
)
from decoy_cli.sim.state import Agents
from decoy_cli.world.physics import AGENT_GROUP, WORLD_GROUP, PhysicsWorld
from decoy_cli.world.world import World

R = PLAYER_RADIUS_M
WALL_X = 3.05  # a wall across the room between x = 0 and x = 6, from y = -5 to 5
PLATFORM_Z = 1.5  # top of a platform east of x = 8


def _room() -> World:
    parts = [
        floor(-10.0, -10.0, 20.0, 10.0),
        wall(WALL_X, -5.0, WALL_X, 5.0, 0.0, 3.0),
        box(8.0, -2.0, 12.0, 2.0, 0.0, PLATFORM_Z),
    ]
    return World(np.concatenate(parts), name="combat room", source="hand-made combat room")


@pytest.fixture(scope="module")
def physics() -> Iterator[PhysicsWorld]:
    with PhysicsWorld(_room()) as world:
        yield world


def _agents(sides: list[str], feet: list[tuple[float, float, float]], **kw) -> Agents:
    n = len(sides)
    return Agents.create(
        [f"p{k}" for k in range(n)], sides, np.array(feet, dtype=float), np.zeros(n), **kw
    )


def _pairs(physics: PhysicsWorld, agents: Agents) -> list[tuple[int, int]]:
    los = LineOfSight(physics, agents.count)
    try:
        pairs = los.visible_pairs(agents)
    finally:
        los.close()
    return list(zip(pairs.attacker.tolist(), pairs.victim.tolist(), strict=True))


# ---- line of sight ----------------------------------------------------------------------------


def test_two_agents_in_the_open_see_each_other(physics: PhysicsWorld) -> None:
    agents = _agents(["T", "CT"], [(0.0, 7.0, 0.0), (6.0, 7.0, 0.0)])
    assert _pairs(physics, agents) == [(0, 1), (1, 0)]


def test_a_wall_blocks_and_the_way_around_it_is_open(physics: PhysicsWorld) -> None:
    agents = _agents(
        ["T", "CT", "CT"], [(0.0, 0.0, 0.0), (6.0, 0.0, 0.0), (4.0, 9.0, 0.0)]
    )  # 0-1 through the wall; 0-2 passes north of its end (y = 5) at y = 6.9
    assert _pairs(physics, agents) == [(0, 2), (2, 0)]


def test_a_third_agent_between_them_blocks_unless_dead(physics: PhysicsWorld) -> None:
    feet = [(-4.0, 7.0, 0.0), (2.0, 7.0, 0.0), (-1.0, 7.0, 0.0)]
    for third in ("T", "CT"):
        agents = _agents(["T", "CT", third], feet)
        pairs = _pairs(physics, agents)
        assert (0, 1) not in pairs and (1, 0) not in pairs
        agents.alive[2] = False
        agents.hp[2] = 0
        assert _pairs(physics, agents) == [(0, 1), (1, 0)]


def test_a_third_agent_beside_the_line_does_not_block(physics: PhysicsWorld) -> None:
    agents = _agents(
        ["T", "CT", "T"], [(-4.0, 7.0, 0.0), (2.0, 7.0, 0.0), (-1.0, 7.0 + R + 0.02, 0)]
    )
    assert (0, 1) in _pairs(physics, agents)


def test_same_side_agents_are_never_paired(physics: PhysicsWorld) -> None:
    agents = _agents(["T", "T", "T"], [(0.0, 7.0, 0.0), (2.0, 7.0, 0.0), (4.0, 7.0, 0.0)])
    assert _pairs(physics, agents) == []
    agents = _agents(["T", "CT", "T", "CT"], [(0, 7, 0), (2, 7.5, 0), (4, 7, 0), (6, 7.5, 0)])
    pairs = _pairs(physics, agents)
    assert pairs == sorted(pairs)
    assert all(agents.side[a] != agents.side[v] for a, v in pairs)
    assert (0, 1) in pairs and (2, 3) in pairs  # neighbours see each other


def test_dead_agents_neither_see_nor_are_seen(physics: PhysicsWorld) -> None:
    agents = _agents(["T", "CT", "CT"], [(0.0, 7.0, 0.0), (6.0, 7.0, 0.0), (6.0, 8.0, 0.0)])
    agents.alive[1] = False
    assert _pairs(physics, agents) == [(0, 2), (2, 0)]
    agents.alive[0] = False
    assert _pairs(physics, agents) == []


def test_looking_down_from_a_platform_in_either_index_order(physics: PhysicsWorld) -> None:
    """A ray leaving its own capsule downwards is what Bullet reports as a hit at fraction 0;
    the line of sight must not take that for a blocker."""
    up = (10.0, 0.0, PLATFORM_Z)
    down = (5.0, 0.0, 0.0)
    assert _pairs(physics, _agents(["T", "CT"], [up, down])) == [(0, 1), (1, 0)]
    assert _pairs(physics, _agents(["T", "CT"], [down, up])) == [(0, 1), (1, 0)]
    # with a third agent far off the line, the capsule rays are cast too
    far = (0.0, 9.0, 0.0)
    assert (0, 1) in _pairs(physics, _agents(["T", "CT", "T"], [up, down, far]))
    # a third agent on the platform in front of the one up there blocks the line
    middle = (8.6, 0.0, PLATFORM_Z)
    assert _pairs(physics, _agents(["T", "CT", "T"], [up, down, middle])) == [(1, 2), (2, 1)]
    assert _pairs(physics, _agents(["T", "CT", "T"], [down, up, middle])) == [(1, 2), (2, 1)]


def test_the_platform_edge_hides_an_agent_standing_close_below_it(physics: PhysicsWorld) -> None:
    agents = _agents(["T", "CT"], [(11.5, 0.0, PLATFORM_Z), (7.7, 0.0, 0.0)])
    assert _pairs(physics, agents) == []


def test_agents_sharing_one_spot_see_each_other(physics: PhysicsWorld) -> None:
    agents = _agents(["T", "CT", "T"], [(0.0, 7.0, 0.0), (0.1, 7.0, 0.0), (5.0, 7.0, 0.0)])
    assert (0, 1) in _pairs(physics, agents)
    agents.position[1] = agents.position[0]
    assert (0, 1) in _pairs(physics, agents)


def test_the_capsules_touch_nothing_and_other_agent_bodies_do_not_block(
    physics: PhysicsWorld,
) -> None:
    agents = _agents(["T", "CT"], [(0.0, 7.0, 0.0), (6.0, 7.0, 0.0)])
    los = LineOfSight(physics, agents.count)
    try:
        assert len(los.visible_pairs(agents)) == 2
        p, client = pybullet, physics.client
        # an agent capsule of another module (group AGENT_GROUP) between them is not seen
        shape = p.createCollisionShape(
            p.GEOM_CAPSULE, radius=R, height=PLAYER_HEIGHT_M - 2 * R, physicsClientId=client
        )
        other = p.createMultiBody(
            baseMass=0,
            baseCollisionShapeIndex=shape,
            basePosition=[3.0, 7.0, PLAYER_HEIGHT_M / 2],
            physicsClientId=client,
        )
        p.setCollisionFilterGroupMask(other, -1, AGENT_GROUP, WORLD_GROUP, physicsClientId=client)
        assert len(los.visible_pairs(agents)) == 2
        p.performCollisionDetection(physicsClientId=client)
        for body in los.bodies:
            assert p.getContactPoints(bodyA=body, physicsClientId=client) == ()
        p.removeBody(other, physicsClientId=client)
        # capsule overlap tests against the world ignore the line-of-sight capsules
        centres = agents.position + np.array([0.0, 0.0, PLAYER_HEIGHT_M / 2])
        in_wall = [[WALL_X, 0.0, PLAYER_HEIGHT_M / 2]]
        blocked = physics.capsules_blocked(np.vstack([centres, in_wall]), R, PLAYER_HEIGHT_M)
        assert blocked.tolist() == [False, False, True]
        assert len(los.visible_pairs(agents)) == 2
    finally:
        los.close()


def test_close_gives_the_capsules_back_for_the_next_round() -> None:
    with PhysicsWorld(_room()) as physics:
        before = pybullet.getNumBodies(physicsClientId=physics.client)
        los = LineOfSight(physics, 7)
        lent = list(los.bodies)
        assert pybullet.getNumBodies(physicsClientId=physics.client) == before + 7
        los.close()
        with pytest.raises(ValueError, match="closed"):
            los.visible_pairs(_agents(["T"] * 7, [(k, 7.0, 0.0) for k in range(7)]))
        # the next round borrows them: only the two more are new, parked until placed
        again = LineOfSight(physics, 9)
        try:
            assert set(lent) <= set(again.bodies)
            assert pybullet.getNumBodies(physicsClientId=physics.client) == before + 9
            for body in again.bodies:
                where, _ = pybullet.getBasePositionAndOrientation(
                    body, physicsClientId=physics.client
                )
                assert where[2] < -1000.0  # parked far below the map
            sides = ["T"] * 5 + ["CT"] * 4
            assert len(again.visible_pairs(_agents(sides, [(k, 7.0, 0.0) for k in range(9)])))
        finally:
            again.close()
        assert pybullet.getNumBodies(physicsClientId=physics.client) == before + 9


def test_bad_arguments_are_refused(physics: PhysicsWorld) -> None:
    with pytest.raises(ValueError, match="radius"):
        LineOfSight(physics, 2, radius=1.0, height=1.0)
    with pytest.raises(ValueError, match="eye height"):
        LineOfSight(physics, 2, eye_height=2.0)
    los = LineOfSight(physics, 3)
    try:
        with pytest.raises(ValueError, match="holds 3 agents"):
            los.visible_pairs(_agents(["T", "CT"], [(0, 7, 0), (6, 7, 0)]))
        agents = _agents(["T", "CT", "T"], [(0, 7, 0), (6, 7, 0), (1, 7, 0)])
        agents.position[2, 0] = np.nan
        with pytest.raises(ValueError, match="NaN"):
            los.visible_pairs(agents)
    finally:
        los.close()


def _segment_capsule_distance(a: np.ndarray, b: np.ndarray, c0: np.ndarray, c1: np.ndarray):
    """Distance between segment a-b and a vertical axis segment c0-c1, by dense sampling of
    the first segment and exact distance of each sample to the axis (an independent oracle)."""
    t = np.linspace(0.0, 1.0, 4001)[:, None]
    points = a + t * (b - a)
    z = np.clip(points[:, 2], c0[2], c1[2])
    return float(np.min(np.hypot(np.hypot(*(points[:, :2] - c0[:2]).T), points[:, 2] - z)))


def test_bodies_block_as_the_capsule_geometry_says() -> None:
    """Random agents at several heights over a deep floor: the line of sight matches a
    geometric oracle (a pair is blocked iff another alive agent's capsule meets the segment
    between the eyes), except for grazes within 5 mm of a capsule's surface."""
    world = World(floor(-20.0, -20.0, 20.0, 20.0, z=-5.0), name="deep floor", source="hand-made")
    rng = np.random.default_rng(7)
    compared = blocked = 0
    with PhysicsWorld(world) as physics:
        los = LineOfSight(physics, 10)
        for _ in range(12):
            feet: list[np.ndarray] = []
            while len(feet) < 10:
                point = np.r_[rng.uniform(-3.0, 3.0, 2), rng.choice([0.0, 0.0, 0.8, 2.5, -1.5])]
                if all(np.hypot(*(point[:2] - q[:2])) > 2 * R + 0.02 for q in feet):
                    feet.append(point)
            agents = _agents(["T", "CT"] * 5, [tuple(f) for f in feet])
            agents.alive[rng.random(10) < 0.2] = False
            pairs = los.visible_pairs(agents)
            seen = set(zip(pairs.attacker.tolist(), pairs.victim.tolist(), strict=True))
            eyes = agents.position + np.array([0.0, 0.0, EYE_HEIGHT_M])
            for a in range(10):
                for v in range(10):
                    if not (agents.alive[a] and agents.alive[v]) or agents.side[a] == "CT":
                        continue
                    if agents.side[v] == "T":
                        continue
                    gaps = [
                        _segment_capsule_distance(
                            eyes[a],
                            eyes[v],
                            agents.position[k] + [0.0, 0.0, R],
                            agents.position[k] + [0.0, 0.0, PLAYER_HEIGHT_M - R],
                        )
                        - R
                        for k in range(10)
                        if agents.alive[k] and k not in (a, v)
                    ]
                    if gaps and min(abs(g) for g in gaps) < 5e-3:
                        continue
                    visible = not gaps or min(gaps) > 0
                    assert ((a, v) in seen) == visible, (a, v, agents.position)
                    assert ((v, a) in seen) == visible
                    compared += 1
                    blocked += not visible
        los.close()
    assert compared > 150 and 10 < blocked < compared - 10


# ---- the combat batch -------------------------------------------------------------------------


def _batch(agents: Agents, pairs: list[tuple[int, int]], map_name: str = "de_dust2"):
    a, v = (np.array(x, dtype=np.int64) for x in zip(*pairs, strict=True))
    return make_batch(agents, VisiblePairs(a, v), map_name)


def test_batch_fields_and_distance() -> None:
    agents = _agents(
        ["T", "CT", "CT", "CT", "CT"],
        [(0, 0, 0), (0, 5, 0), (0, -5, 1), (-5, 0, 0), (0, 0, 3)],
        weapons=["AK-47", "M4A4", "AWP", "USP-S", "Knife"],
        hp=np.array([90, 80, 70, 60, 50]),
        armor=np.array([0, 100, 50, 0, 0]),
        helmet=np.array([False, True, False, False, False]),
        yaw=np.array([0.0, 10.0, 20.0, 30.0, 40.0]),
    )
    batch = _batch(agents, [(0, 1), (0, 2), (0, 3), (0, 4), (1, 0)], "de_dust2")
    assert isinstance(batch, CombatBatch) and len(batch) == 5
    assert batch.map_name == "de_dust2"
    np.testing.assert_allclose(batch.distance, [5.0, np.hypot(5, 1), 5.0, 3.0, 5.0])
    assert batch.attacker_weapon.tolist() == ["AK-47"] * 4 + ["M4A4"]
    assert batch.attacker_hp.tolist() == [90, 90, 90, 90, 80]
    assert batch.victim_hp.tolist() == [80, 70, 60, 50, 90]
    assert batch.victim_armor.tolist() == [100, 50, 0, 0, 0]
    assert batch.victim_helmet.tolist() == [True, False, False, False, False]
    np.testing.assert_allclose(batch.attacker_yaw, [0, 0, 0, 0, 10])
    np.testing.assert_allclose(batch.victim_yaw, [10, 20, 30, 40, 0])
    np.testing.assert_allclose(batch.victim_position[1], [0, -5, 1])
    # a copy: the agents change afterwards, the batch does not
    agents.position[1] = [9, 9, 9]
    agents.hp[0] = 1
    np.testing.assert_allclose(batch.victim_position[0], [0, 5, 0])
    assert batch.attacker_hp[0] == 90


def test_batches_join_in_order_and_keep_their_map() -> None:
    agents = _agents(["T", "CT", "CT"], [(0, 0, 0), (0, 5, 0), (3, 0, 4)])
    first, second = _batch(agents, [(0, 1)]), _batch(agents, [(0, 2), (1, 0)])
    joined = CombatBatch.concat([first, second])
    assert joined.attacker.tolist() == [0, 0, 1] and joined.victim.tolist() == [1, 2, 0]
    np.testing.assert_allclose(joined.distance, [5.0, 5.0, 5.0])
    assert joined.map_name == "de_dust2"
    for name in PAIR_FIELDS:
        assert len(getattr(joined, name)) == 3
    with pytest.raises(ValueError, match="one map"):
        CombatBatch.concat([first, _batch(agents, [(0, 1)], "de_nuke")])


# ---- damage -----------------------------------------------------------------------------------


CHEST = HIT_GROUPS.index("Chest")


class WithinTenMetres:
    """Test model: an attacker within 10 m hits the chest for `damage` HP, farther misses."""

    def __init__(self, damage: int = 30) -> None:
        self.damage = damage
        self.calls = 0

    def __call__(self, batch: CombatBatch, rng: np.random.Generator) -> DamageResult:
        self.calls += 1
        hit = batch.distance <= 10.0
        return DamageResult(
            damage=np.where(hit, self.damage, 0),
            hit_group=np.where(hit, CHEST, -1).astype(np.int8),
            hit=hit,
        )


class CoinFlip:
    """Test model that uses the generator: each pair hits with probability 1/2 for 1..40 HP."""

    def __call__(self, batch: CombatBatch, rng: np.random.Generator) -> DamageResult:
        hit = rng.random(len(batch)) < 0.5
        damage = np.where(hit, rng.integers(1, 41, len(batch)), 0)
        group = np.where(hit, rng.integers(0, len(HIT_GROUPS), len(batch)), -1)
        return DamageResult(damage=damage, hit_group=group, hit=hit)


def test_mutual_kill_in_one_step(physics: PhysicsWorld) -> None:
    agents = _agents(
        ["T", "CT"],
        [(0.0, 7.0, 0.0), (5.0, 7.0, 0.0)],
        hp=np.array([20, 25]),
        weapons=["AK-47", "AWP"],
    )
    los = LineOfSight(physics, 2)
    try:
        events = CombatStep(los, WithinTenMetres(), "de_dust2").run(
            agents, 30, np.random.default_rng(0)
        )
    finally:
        los.close()
    assert agents.hp.tolist() == [0, 0] and agents.hp.dtype == np.int16
    assert agents.alive.tolist() == [False, False]
    assert [(e.tick, e.kind, e.agent, e.other) for e in events] == [
        (30, "damage", 0, 1),
        (30, "damage", 1, 0),
        (30, "kill", 1, 0),
        (30, "kill", 0, 1),
    ]
    assert events[0].data == {"damage": 30, "hit_group": CHEST, "weapon": "AK-47", "hp_after": 0}
    assert events[3].data == {"weapon": "AK-47", "hit_group": CHEST}


def test_damage_is_summed_over_attackers_and_clipped_at_zero() -> None:
    agents = _agents(["T", "CT", "CT", "CT"], [(0, 0, 0), (1, 0, 0), (2, 0, 0), (30, 0, 0)])
    agents.hp[0] = 70
    batch = _batch(agents, [(1, 0), (2, 0), (3, 0)])  # agent 3 is 30 m away: a miss
    events = apply_damage(agents, batch, WithinTenMetres()(batch, None), 60)
    assert agents.hp.tolist() == [10, 100, 100, 100]
    assert agents.alive.all()
    assert [e.data["hp_after"] for e in events] == [10, 10] and len(events) == 2
    events = apply_damage(agents, batch, WithinTenMetres(damage=99)(batch, None), 90)
    assert agents.hp.tolist() == [0, 100, 100, 100] and not agents.alive[0]
    assert [e.kind for e in events] == ["damage", "damage", "kill"]


def _result(damage: list[int]) -> DamageResult:
    hit = np.array(damage) > 0
    return DamageResult(np.array(damage), np.where(hit, CHEST, -1), hit)


def test_kill_credit_goes_to_the_most_damage_then_the_lowest_index() -> None:
    agents = _agents(["T", "T", "T", "CT"], [(0, 0, 0), (1, 0, 0), (2, 0, 0), (3, 0, 0)])
    batch = _batch(agents, [(0, 3), (1, 3), (2, 3)])
    events = apply_damage(agents, batch, _result([20, 40, 40]), 30)
    assert [(e.kind, e.agent, e.other) for e in events if e.kind == "kill"] == [("kill", 1, 3)]
    agents = _agents(["T", "T", "T", "CT"], [(0, 0, 0), (1, 0, 0), (2, 0, 0), (3, 0, 0)])
    events = apply_damage(agents, batch, _result([20, 30, 50]), 30)
    assert [(e.kind, e.agent) for e in events if e.kind == "kill"] == [("kill", 2)]
    agents = _agents(["T", "T", "T", "CT"], [(0, 0, 0), (1, 0, 0), (2, 0, 0), (3, 0, 0)])
    events = apply_damage(agents, batch, _result([20, 0, 79]), 30)
    assert [e.kind for e in events] == ["damage", "damage"] and agents.hp[3] == 1


def test_damage_results_and_batches_are_checked() -> None:
    with pytest.raises(ValueError, match="negative"):
        DamageResult(np.array([-1]), np.array([2]), np.array([True]))
    with pytest.raises(ValueError, match="miss"):
        DamageResult(np.array([5]), np.array([-1]), np.array([False]))
    with pytest.raises(ValueError, match="integers"):
        DamageResult(np.array([5.5]), np.array([2]), np.array([True]))
    with pytest.raises(ValueError, match="hit group"):
        DamageResult(np.array([5]), np.array([6]), np.array([True]))
    with pytest.raises(ValueError, match="one length"):
        DamageResult(np.array([5, 5]), np.array([2]), np.array([True]))
    agents = _agents(["T", "CT"], [(0, 0, 0), (1, 0, 0)])
    batch = _batch(agents, [(0, 1), (1, 0)])
    with pytest.raises(ValueError, match="for 1 pairs"):
        apply_damage(agents, batch, _result([5]), 30)
    agents.alive[1] = False
    with pytest.raises(ValueError, match="dead"):
        apply_damage(agents, batch, _result([5, 5]), 30)
    with pytest.raises(ValueError, match="outside"):
        make_batch(agents, VisiblePairs(np.array([0]), np.array([2])), "de_dust2")


def test_no_visible_pair_calls_no_model(physics: PhysicsWorld) -> None:
    model = WithinTenMetres()
    agents = _agents(["T", "CT"], [(0.0, 0.0, 0.0), (6.0, 0.0, 0.0)])  # the wall between
    los = LineOfSight(physics, 2)
    try:
        step = CombatStep(los, model, "de_dust2")
        assert step.run(agents, 30, np.random.default_rng(0)) == []
        agents.alive[1] = False
        agents.position[1] = [0.5, 0.0, 0.0]
        assert step.run(agents, 60, np.random.default_rng(0)) == []
    finally:
        los.close()
    assert model.calls == 0 and agents.hp.tolist() == [100, 100]


def test_a_step_is_deterministic_for_a_seed(physics: PhysicsWorld) -> None:
    feet = [(x, 6.0 + 0.8 * (k % 3), 0.0) for k, x in enumerate(np.linspace(-8.0, 8.0, 10))]
    runs = []
    for _ in range(2):
        agents = _agents(["T", "CT"] * 5, feet)
        los = LineOfSight(physics, 10)
        step = CombatStep(los, CoinFlip(), "de_dust2")
        rng = np.random.default_rng(11)
        try:
            events = [e for tick in (30, 60, 90) for e in step.run(agents, tick, rng)]
        finally:
            los.close()
        runs.append((events, agents.hp.copy()))
    assert runs[0][0] == runs[1][0] and np.array_equal(runs[0][1], runs[1][1])
    assert any(e.kind == "damage" for e in runs[0][0])


def test_armour_goes_down_by_the_result_and_stays_at_or_above_zero() -> None:
    agents = _agents(["T", "T", "CT"], [(0, 0, 0), (1, 0, 0), (2, 0, 0)])
    agents.armor[2] = 10
    batch = _batch(agents, [(0, 2), (1, 2)])
    result = DamageResult(
        np.array([27, 20]), np.array([CHEST, CHEST]), np.array([True, True]), np.array([4, 8])
    )
    apply_damage(agents, batch, result, 30)
    assert agents.armor[2] == 0 and agents.hp[2] == 100 - 47
    agents.armor[2] = 50
    apply_damage(agents, batch, _result([5, 5]), 60)  # a model of HP only leaves armour alone
    assert agents.armor[2] == 50
    with pytest.raises(ValueError, match="armor_damage"):
        DamageResult(np.array([5]), np.array([2]), np.array([True]), np.array([-1]))
    with pytest.raises(ValueError, match="armor_damage"):
        DamageResult(np.array([0]), np.array([-1]), np.array([False]), np.array([3]))


# ---- aim ---------------------------------------------------------------------------------------


class Bearings:
    """A model that hits nobody and keeps each step's bearings, by (attacker, victim)."""

    def __init__(self) -> None:
        self.steps: list[dict[tuple[int, int], float]] = []

    def __call__(self, batch: CombatBatch, rng: np.random.Generator) -> DamageResult:
        pairs = zip(batch.attacker.tolist(), batch.victim.tolist(), strict=True)
        delta = batch.victim_position - batch.attacker_position
        seen = np.degrees(bearing(delta[:, 0], delta[:, 1], batch.attacker_yaw))
        self.steps.append(dict(zip(pairs, seen.tolist(), strict=True)))
        k = len(batch)
        return DamageResult(np.zeros(k, np.int64), np.full(k, -1), np.zeros(k, bool))


def test_an_agent_aims_at_an_enemy_in_sight_for_a_reaction_time(physics: PhysicsWorld) -> None:
    """At first sight both look where they were going; an enemy still in sight a reaction time
    later is aimed at, the nearest where several are; out of sight, the aim starts again."""
    agents = _agents(
        ["T", "CT", "CT"], [(-6.0, 6.0, 0.0), (6.0, 6.0, 0.0), (-6.0, 9.0, 0.0)],
        yaw=np.array([90.0, 90.0, 0.0]),
    )  # fmt: skip
    model = Bearings()
    los = LineOfSight(physics, 3)
    step = CombatStep(los, model, "de_dust2")
    reaction = int(np.ceil(REACTION_S * TICK_RATE))
    rng = np.random.default_rng(0)
    try:
        for tick in (30, 30 + reaction - 1, 30 + reaction):
            step.run(agents, tick, rng)
        agents.position[2] = [6.0, 0.0, 0.0]  # behind the wall for one step, then back
        agents.position[1] = [0.0, 12.0, 0.0]
        step.run(agents, 90, rng)
        agents.position[2] = [-6.0, 9.0, 0.0]
        step.run(agents, 120, rng)
    finally:
        los.close()
    first, early, aimed, _, back = model.steps
    assert first[(0, 1)] == pytest.approx(-90.0) and first[(0, 2)] == pytest.approx(0.0)
    assert early == first  # not yet a reaction time
    assert aimed[(0, 2)] == pytest.approx(0.0)  # the nearer one, 3 m north
    assert aimed[(0, 1)] == pytest.approx(-90.0) and aimed[(1, 0)] == pytest.approx(0.0)
    assert aimed[(2, 0)] == pytest.approx(0.0)  # looking south at him since 30
    assert (2, 0) not in model.steps[3]
    assert back[(2, 0)] == pytest.approx(-90.0)  # seen anew: its yaw 0, him due south


def test_aimed_yaw_turns_only_the_agents_that_aim() -> None:
    agents = _agents(["T", "CT", "CT"], [(0, 0, 0), (0, 4, 0), (3, 0, 0)], yaw=np.full(3, 45.0))
    pairs = VisiblePairs(np.array([0, 0, 1, 2]), np.array([1, 2, 0, 0]))
    yaw = aimed_yaw(agents, pairs, np.array([True, True, False, True]))
    np.testing.assert_allclose(yaw, [0.0, 45.0, 180.0])  # 0 aims at the nearer, 2 due west
    assert agents.yaw.tolist() == [45.0] * 3  # the agents' own yaw is left alone


def test_a_step_with_nobody_in_sight_forgets_who_was(physics: PhysicsWorld) -> None:
    agents = _agents(["T", "CT"], [(0.0, 0.0, 0.0), (0.0, 8.0, 0.0)], yaw=np.zeros(2))
    model = Bearings()
    los = LineOfSight(physics, 2)
    step = CombatStep(los, model, "de_dust2")
    rng = np.random.default_rng(0)
    try:
        for tick, north in ((30, True), (60, False), (90, True), (120, True)):
            agents.position[1] = [0.0, 8.0, 0.0] if north else [6.0, 0.0, 0.0]  # or behind the wall
            step.run(agents, tick, rng)
    finally:
        los.close()
    first, seen_anew, aimed = model.steps  # the step at 60 saw nobody: no model call
    assert first[(0, 1)] == pytest.approx(90.0) and seen_anew[(0, 1)] == pytest.approx(90.0)
    assert aimed[(0, 1)] == pytest.approx(0.0)
