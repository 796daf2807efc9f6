"""Falls as in CS:GO: the damage rule at its thresholds, drop edges deeper than the safe fall
built and verified by the physics mover, and fall damage (and death) where an agent lands."""

from __future__ import annotations

import numpy as np
import pytest
from worlds import CLIFF, CLIFF_Z, cliff_world, seeds_of

from decoy_cli.csgo import HAMMER_TO_M, MAX_DROP_M, SAFE_DROP_M, fall_damage
from decoy_cli.sim.engine import Decision, Simulator
from decoy_cli.sim.movement import KinematicMover, PhysicsMover
from decoy_cli.sim.rules import BombRules, RulesConfig, SiteZones
from decoy_cli.sim.state import Agents
from decoy_cli.waypoints.build import build_graph
from decoy_cli.waypoints.graph import STOP_ACTION, EdgeKind
from decoy_cli.world.physics import PhysicsWorld


@pytest.mark.parametrize(
    ("height_u", "damage"),
    [
        (0.0, 0),
        (210.0, 0),  # 580 u/s: the safe fall
        (226.0, 5),  # sqrt(1600 * 226) = 601.3 u/s: 21.3 * 100 / 420 = 5.07
        (300.0, 27),  # 692.8 u/s: 26.9
        (400.0, 52),  # 800 u/s: 52.4
        (620.0, 99),  # 996.0 u/s: 99.0, the deepest drop the builder links
        (625.0, 100),  # 1000 u/s: fatal
    ],
)
def test_the_fall_damage_rule(height_u: float, damage: int) -> None:
    assert fall_damage(height_u * HAMMER_TO_M) == damage


def test_the_drop_limits() -> None:
    assert round(SAFE_DROP_M / HAMMER_TO_M, 2) == 210.25
    assert fall_damage(MAX_DROP_M) < 100 <= fall_damage(MAX_DROP_M + 0.1)


@pytest.fixture(scope="module")
def cliff():
    world = cliff_world()
    graph, _ = build_graph(world, seeds=seeds_of(world))
    return world, graph


def test_a_cliff_deeper_than_the_safe_fall_is_a_verified_drop_edge(cliff) -> None:
    _, graph = cliff
    deep = np.flatnonzero(graph.fall_m > 0)
    assert np.all(graph.edge_kind[deep] == EdgeKind.DROP)
    assert np.all(graph.fall_m[deep] > SAFE_DROP_M)  # the plateau's cliffs and the ramp's sides
    from_plateau = deep[graph.positions[graph.edge_source[deep], 2] > CLIFF_Z - 0.05]
    assert len(from_plateau) > 10
    assert np.allclose(graph.fall_m[from_plateau], CLIFF_Z, atol=0.05)
    source = graph.positions[graph.edge_source[from_plateau]]
    x0, y0, x1, y1 = CLIFF
    inside = (source[:, 0] > x0 - 0.5) & (source[:, 0] < x1 + 0.5)
    assert np.all(inside & (source[:, 1] > y0 - 0.5) & (source[:, 1] < y1 + 0.5))
    # the plateau comes back by the ramp: drop edges are part of the strongly connected graph
    assert graph.num_nodes > 500


def cliff_edge(graph) -> int:
    """A drop edge off the plateau (a full `CLIFF_Z` fall)."""
    deep = np.flatnonzero(graph.fall_m > CLIFF_Z - 0.05)
    return int(deep[0])


def _round(graph, mover, hp: list[int], edge: int, kills: bool = True):
    """Two agents on the source of `edge` walking it (health `hp`), and a CT far away (100);
    returns the sim (`kills` False: nothing in it kills, as when deaths follow the data)."""
    start = int(graph.edge_source[edge])
    direction = int(graph.edge_direction[edge])
    far = int(np.argmin(graph.positions[:, 0]))
    nodes = np.array([start, start, far])
    agents = Agents.create(
        ["a", "b", "ct"], ["T", "T", "CT"], graph.positions[nodes], nodes, hp=np.array([*hp, 100])
    )
    zones = SiteZones(nodes={"A": [[100.0, 100.0, 0.0]]})  # nobody can plant
    plans = {0: [Decision(direction)], 1: [Decision(direction)]}

    class Walk:
        def decide(self, sim: Simulator, agent: int) -> Decision:
            plan = plans.get(agent, [])
            return plan.pop(0) if plan else Decision(STOP_ACTION, hold_ticks=10**6)

    rules = BombRules(zones, RulesConfig())
    return Simulator(graph, agents, mover, Walk(), rules, kills=kills, seed=0)


@pytest.mark.parametrize("mover_kind", ["kinematic", "physics"])
def test_landing_from_the_cliff_costs_health_and_can_kill(cliff, mover_kind: str) -> None:
    world, graph = cliff
    edge = cliff_edge(graph)
    damage = fall_damage(float(graph.fall_m[edge]))
    assert damage == 31  # 315 u: 710 u/s
    with PhysicsWorld(world) as physics:
        mover = KinematicMover() if mover_kind == "kinematic" else PhysicsMover(physics)
        sim = _round(graph, mover, [100, damage - 1], edge)
        sim.run(to_tick=300)
    falls = [e for e in sim.events if e.kind == "fall_damage"]
    assert [(e.agent, e.data["damage"]) for e in falls] == [(0, damage), (1, damage)]
    assert sim.agents.hp[0] == 100 - damage and sim.agents.alive[0]
    assert not sim.agents.alive[1] and sim.agents.hp[1] == 0
    deaths = [e for e in sim.events if e.kind == "death"]
    assert [(e.agent, e.data["reason"]) for e in deaths] == [(1, "fall")]
    assert deaths[0].tick == falls[1].tick  # (with capsules, b waits for a to clear the way)


def test_a_fall_kills_nobody_when_deaths_follow_the_data(cliff) -> None:
    """With `kills` off (`--deaths data`: the fight leaves 1 HP, the data says who dies) a fall
    that would kill leaves its 1 HP too: a wounded player who falls is not a death the data
    does not have."""
    _, graph = cliff
    sim = _round(graph, KinematicMover(), [100, 1], cliff_edge(graph), kills=False)
    sim.run(to_tick=300)
    assert [e.agent for e in sim.events if e.kind == "fall_damage"] == [0, 1]
    assert sim.agents.alive.all() and sim.agents.hp[1] == 1
    assert not [e for e in sim.events if e.kind == "death"]


def test_a_fall_that_kills_the_last_t_ends_the_round_on_the_landing_tick(cliff) -> None:
    _, graph = cliff
    edge = cliff_edge(graph)
    sim = _round(graph, KinematicMover(), [5, 5], edge)
    sim.run()
    land = next(e.tick for e in sim.events if e.kind == "fall_damage")
    assert sim.outcome is not None and sim.outcome.winner == "CT"
    end = next(e for e in sim.events if e.kind == "round_end")
    assert end.tick == land


def test_stepping_and_running_land_alike(cliff) -> None:
    """The event-by-event run crosses the fall in a glide; stepping every tick gives the same
    landing, damage, death and end."""
    _, graph = cliff
    edge = cliff_edge(graph)
    stepped = _round(graph, KinematicMover(), [40, 20], edge)
    while not stepped.done:
        stepped.step()
    ran = _round(graph, KinematicMover(), [40, 20], edge)
    ran.run()
    assert [(e.tick, e.kind, e.agent) for e in ran.events] == [
        (e.tick, e.kind, e.agent) for e in stepped.events
    ]
    assert ran.tick == stepped.tick and ran.outcome == stepped.outcome
    np.testing.assert_array_equal(ran.agents.hp, stepped.agents.hp)


def test_random_agents_fall_off_the_cliff_alike_compiled_and_stepped(cliff, monkeypatch) -> None:
    """Random agents on the plateau take its drops; in compiled stretches (`quiet_play`) a
    damaging drop hands the tick back to Python, which lands it as stepping does."""
    from busy_rounds import count_stretch_decisions, random_round

    _, graph = cliff
    plateau = np.flatnonzero(graph.positions[:, 2] > CLIFF_Z - 0.05)
    made = count_stretch_decisions(monkeypatch)

    def play(seed: int, compiled: bool) -> Simulator:
        nodes = np.random.default_rng(seed).choice(plateau, 8, replace=False)
        return random_round(graph, nodes, seed, compiled, ticks=3000, every=9)

    falls = 0
    for seed in range(4):
        stepped, compiled = play(seed, compiled=False), play(seed, compiled=True)
        assert compiled.events == stepped.events, seed
        assert compiled.tick == stepped.tick and compiled.outcome == stepped.outcome
        np.testing.assert_array_equal(compiled.recording.position, stepped.recording.position)
        np.testing.assert_array_equal(compiled.agents.hp, stepped.agents.hp)
        falls += sum(e.kind == "fall_damage" for e in stepped.events)
    assert falls >= 4 and sum(made) > 100
