"""Scripted rounds (decoy_cli/synth): routes, loadouts, the policy's objectives, and a generated
two-round match read back by `read_match` with both teams' frames, consistent events and a valid
outcome; determinism; and the sample replayed by the replay pipeline.

Combat uses `FixedDamage` below, a hand-written damage model (a hit with a fixed probability
for a fixed damage), not a learned one.
"""

from __future__ import annotations

import numpy as np
import pytest

from decoy_cli.esta import Match, read_match
from decoy_cli.esta.records import AWPY_HIT_GROUPS
from decoy_cli.esta.writer import encode_match, write_match
from decoy_cli.metrics import player_metrics
from decoy_cli.replay.replayer import ReplayOptions, replay_round
from decoy_cli.sim.combat import HIT_GROUPS, NO_HIT, CombatBatch, DamageResult
from decoy_cli.sim.rules import SiteZones
from decoy_cli.sim.state import BombStatus
from decoy_cli.synth import SampleMatch, play_match, sample_file_name
from decoy_cli.synth.loadouts import BUY_KINDS, buy_kind, side_loadouts
from decoy_cli.synth.player import RoundScript, open_scripted_round, scripted_setup
from decoy_cli.synth.routes import (
    CT_ROLES,
    CT_SETUPS,
    SITE_PLACES,
    T_STRATEGIES,
    Places,
    plan_round,
)
from decoy_cli.synth.sample import TEAM
from decoy_cli.waypoints.build import builtin_graph
from decoy_cli.weapons import WEAPONS, is_known
from decoy_cli.world.navmesh import nav_world
from decoy_cli.world.physics import PhysicsWorld

SEED = 5
END_REASONS = {"TargetBombed", "BombDefused", "CTWin", "TerroristsWin", "TargetSaved"}
BOMB_OR_TIME = {"TargetBombed", "BombDefused", "TargetSaved"}
FRAME_TICKS = 64


class FixedDamage:
    """Every visible pair hits with probability `probability` for `damage` HP; the hit group
    cycles with the pair so that every group (arms and legs too) occurs."""

    def __init__(self, probability: float = 0.35, damage: int = 27) -> None:
        self.probability = probability
        self.damage = damage

    def __call__(self, batch: CombatBatch, rng: np.random.Generator) -> DamageResult:
        hit = rng.random(len(batch)) < self.probability
        group = np.where(hit, (batch.attacker + 3 * batch.victim) % len(HIT_GROUPS), NO_HIT)
        damage = np.where(hit, self.damage, 0).astype(np.int64)
        return DamageResult(damage, group.astype(np.int8), hit)


@pytest.fixture(scope="module")
def graph():
    return builtin_graph()


@pytest.fixture(scope="module")
def combat(tmp_path_factory: pytest.TempPathFactory) -> tuple[SampleMatch, Match]:
    sample = play_match(2, SEED, FixedDamage(), "test")
    path = write_match(sample.match, tmp_path_factory.mktemp("synth") / sample_file_name(SEED))
    return sample, read_match(path)


@pytest.fixture(scope="module")
def quiet(tmp_path_factory: pytest.TempPathFactory) -> tuple[SampleMatch, Match]:
    sample = play_match(2, 1, None, "none")
    path = write_match(sample.match, tmp_path_factory.mktemp("quiet") / sample_file_name(1))
    return sample, read_match(path)


def test_both_teams_frames(combat: tuple[SampleMatch, Match]) -> None:
    sample, match = combat
    assert match.round_errors == {} and len(match.rounds) == 2
    for played, r in zip(sample.rounds, match.rounds, strict=True):
        record = played.record
        assert [p.name for p in r.players] == list(TEAM.names)
        assert [p.side for p in r.players] == ["T"] * 5 + ["CT"] * 5
        assert r.present.all()
        assert np.all(np.diff(r.frame_ticks) == FRAME_TICKS)
        np.testing.assert_allclose(r.frame_seconds, 0.5 * np.arange(r.num_frames))
        np.testing.assert_allclose(r.position, record.position, rtol=1e-6, atol=1e-9)
        np.testing.assert_array_equal(r.hp, record.hp)
        np.testing.assert_array_equal(r.alive, record.alive)
        assert r.frame_ticks[-1] <= r.end_tick < r.frame_ticks[-1] + FRAME_TICKS
        assert r.has_bomb.sum(axis=0).max() == 1  # one carrier at a time
        assert all(is_known(w) for w in np.unique(r.weapon))


def test_hp_and_deaths_follow_the_events(combat: tuple[SampleMatch, Match]) -> None:
    _, match = combat
    kills = 0
    groups: set[str] = set()
    for r in match.rounds:
        assert len(r.damages) > 0
        kills += len(r.kills)
        groups |= set(r.damages["hitGroup"])
        for i, player in enumerate(r.players):
            mine = r.damages[r.damages["victimName"] == player.name]
            for j, tick in enumerate(r.frame_ticks):
                taken = int(mine.loc[mine["tick"] <= tick, "hpDamageTaken"].sum())
                assert r.hp[i, j] == 100 - taken, (player.name, j)
            died = r.kills[r.kills["victimName"] == player.name]
            assert len(died) == (0 if r.alive[i, -1] else 1)
            if len(died):
                first_dead = int(np.argmax(~r.alive[i]))
                assert r.frame_ticks[first_dead] == died["tick"].iloc[0]
                killer = died["attackerName"].iloc[0]
                assert died["attackerSide"].iloc[0] != player.side
                k = [p.name for p in r.players].index(killer)
                # the killer's weapon in the frame before (it may die in the same step)
                assert died["weapon"].iloc[0] == r.weapon[k, first_dead - 1]
    assert kills > 0
    assert groups <= set(AWPY_HIT_GROUPS)  # arms and legs get awpy's left/right names
    assert groups & {"LeftArm", "RightArm"} and groups & {"LeftLeg", "RightLeg"}


def test_outcome_is_valid_and_consistent(combat: tuple[SampleMatch, Match]) -> None:
    sample, match = combat
    for played, r in zip(sample.rounds, match.rounds, strict=True):
        assert played.invalid_actions == 0
        assert r.end_reason in END_REASONS
        actions = list(r.bomb_events["bombAction"])
        t_alive = r.alive[:5, -1].any()
        ct_alive = r.alive[5:, -1].any()
        planted = "plant" in actions
        if planted:
            assert r.bomb_plant_tick == int(r.bomb_events.loc[actions.index("plant"), "tick"])
            np.testing.assert_array_equal(r.bomb_planted, r.frame_ticks >= r.bomb_plant_tick)
            site = r.bomb_events["bombSite"].iloc[actions.index("plant")]
            assert set(r.bombsite[r.bomb_planted]) == {site}
        else:
            assert r.bomb_plant_tick is None and not r.bomb_planted.any()
        expected_winner = "CT" if r.end_reason in {"CTWin", "BombDefused", "TargetSaved"} else "T"
        assert r.winning_side == expected_winner
        if r.end_reason == "TerroristsWin":
            assert not ct_alive
        elif r.end_reason == "CTWin":
            assert not t_alive and not planted
        elif r.end_reason == "TargetBombed":
            explode = int(r.bomb_events.loc[actions.index("explode"), "tick"])
            assert explode - r.bomb_plant_tick == pytest.approx(40 * 128, abs=2)
        elif r.end_reason == "BombDefused":
            assert "defuse" in actions
        else:
            assert not planted and (r.end_tick - played.record.freeze_end_tick) >= 115 * 128


def test_provenance_says_synthetic(combat: tuple[SampleMatch, Match]) -> None:
    _, match = combat
    assert match.match_id == f"synthetic-dust2-seed{SEED}"
    assert match.map_name == "de_dust2" and match.tick_rate == 128
    provenance = match.meta["provenance"]
    assert provenance["synthetic"] is True and provenance["combat"] is True
    assert provenance["damage_models"] == "test" and provenance["seed"] == SEED
    assert match.meta["clientName"] == "decoy make-sample"
    assert match.meta["parserParameters"]["parseRate"] == 64


def test_same_seed_same_bytes(combat: tuple[SampleMatch, Match]) -> None:
    sample, _ = combat
    again = play_match(2, SEED, FixedDamage(), "test")
    assert encode_match(again.match) == encode_match(sample.match)
    other = play_match(1, SEED + 1, FixedDamage(), "test")
    assert not np.array_equal(other.rounds[0].record.position, sample.rounds[0].record.position)


def test_without_combat_rounds_end_by_bomb_or_time(quiet: tuple[SampleMatch, Match]) -> None:
    sample, match = quiet
    assert match.meta["provenance"]["combat"] is False
    for played, r in zip(sample.rounds, match.rounds, strict=True):
        assert len(r.damages) == 0 and len(r.kills) == 0 and r.alive.all()
        assert r.end_reason in BOMB_OR_TIME
        if r.bomb_plant_tick is not None:
            # every CT rotated to the planted bomb and waits at it
            after = r.frame_ticks >= r.bomb_plant_tick + 30 * 128
            bomb = r.bomb_position[after]
            ct = r.position[5:, after]
            assert np.linalg.norm(ct - bomb[None], axis=2).max() < 2.0
        assert played.invalid_actions == 0


def test_dropped_bomb_is_picked_up_and_planted(graph) -> None:
    places = Places(graph)
    zones = SiteZones.from_graph(graph)
    rng = np.random.default_rng(11)
    plan = plan_round(places, zones, rng)
    loadouts = side_loadouts("T", "full", 5, rng) + side_loadouts("CT", "full", 5, rng)
    script = RoundScript(places=places, plan=plan, loadouts=loadouts, team=TEAM)
    with open_scripted_round(scripted_setup(graph, None), script, seed=0) as sim:
        sim.kill(plan.carrier, "test")
        sim.run()
    kinds = [(e.kind, e.agent) for e in sim.events]
    assert ("bomb_drop", plan.carrier) in kinds
    picker = next(agent for kind, agent in kinds if kind == "bomb_pickup")
    assert picker != plan.carrier and sim.agents.side[picker] == "T"
    assert ("plant", picker) in kinds
    assert sim.bomb.site == plan.site
    assert sim.outcome is not None and sim.outcome.reason in BOMB_OR_TIME
    assert sim.bomb.status in (BombStatus.EXPLODED, BombStatus.DEFUSED)


@pytest.mark.parametrize("seed", range(8))
def test_routes(graph, seed: int) -> None:
    places = Places(graph)
    zones = SiteZones.from_graph(graph)
    plan = plan_round(places, zones, np.random.default_rng(seed))
    assert plan.strategy in T_STRATEGIES and plan.ct_setup in CT_SETUPS
    assert len(plan.routes) == 10 and 0 <= plan.carrier < 5
    assert zones.site_of(graph.positions[plan.plant_node])[0] == plan.site
    assert plan.routes[plan.carrier][-1].node == plan.plant_node
    t_spawn, ct_spawn = set(places.nodes("TSpawn")), set(places.nodes("CTSpawn"))
    site_nodes = set(places.nodes(SITE_PLACES[plan.site]))
    for route in plan.routes[:5]:
        assert route[0].node in t_spawn and route[-1].node in site_nodes
        assert any(leg.until_tick > 0 for leg in route)  # waits for the execute
    for route, role in zip(plan.routes[5:], CT_SETUPS[plan.ct_setup], strict=True):
        assert route[0].node in ct_spawn
        assert route[-1].node in set(places.nodes(CT_ROLES[role].place))
    starts = [route[0].node for route in plan.routes]
    assert len(set(starts)) == 10
    roles = CT_SETUPS[plan.ct_setup]
    away = {5 + k for k, role in enumerate(roles) if CT_ROLES[role].site != plan.site}
    assert set(plan.rotations) == away and away  # mid, at least, rotates
    assert all(leg.node in site_nodes for leg in plan.rotations.values())


def test_strategies_cover_the_plan() -> None:
    names = {s.name for s in T_STRATEGIES}
    assert names == {"A long", "A short", "B tunnels", "mid to B", "mid to A split"}
    assert all(sum(g.count for g in s.groups) == 5 for s in T_STRATEGIES)
    assert {s.site for s in T_STRATEGIES} == {"A", "B"}


@pytest.mark.parametrize("kind", BUY_KINDS)
@pytest.mark.parametrize("side", ["T", "CT"])
def test_loadouts(kind: str, side: str) -> None:
    loadouts = side_loadouts(side, kind, 5, np.random.default_rng(3))
    for lo in loadouts:
        assert all(name in WEAPONS for name in lo.inventory)
        assert lo.active == (lo.primary or lo.pistol)
        assert WEAPONS[lo.pistol][0] == "Pistols"
        assert lo.value >= 200
        assert not (lo.defuse_kit and side == "T")
    if kind in ("pistol", "eco"):
        assert all(lo.primary is None and not lo.helmet for lo in loadouts)
    if kind == "eco":
        assert all(lo.armor == 0 for lo in loadouts)
    if kind == "full":
        assert all(lo.helmet and lo.armor == 100 for lo in loadouts)
        assert all(WEAPONS[lo.primary][0] == "Rifle" for lo in loadouts if lo.primary)


def test_buy_kinds() -> None:
    rng = np.random.default_rng(0)
    assert buy_kind(0, "T", None, 15, rng) == "pistol"
    assert buy_kind(15, "CT", "T", 15, rng) == "pistol"
    assert buy_kind(1, "T", "T", 15, rng) == "force"
    assert buy_kind(1, "CT", "T", 15, rng) == "eco"
    later = {buy_kind(5, "T", "CT", 15, rng) for _ in range(200)}
    assert later == {"full", "force", "eco"}
    with pytest.raises(ValueError, match="unknown buy kind"):
        side_loadouts("T", "splurge", 5, rng)


def test_play_match_refuses_bad_arguments() -> None:
    with pytest.raises(ValueError, match="1 to 30 rounds"):
        play_match(0, 0, None, "none")
    with pytest.raises(ValueError, match="seed must be >= 0"):
        play_match(1, -1, None, "none")


def test_the_sample_replays(graph, quiet: tuple[SampleMatch, Match]) -> None:
    """The replay pipeline (what `decoy evaluate` runs) takes the sample: rounds made on the
    same graph replay close to their own frames."""
    _, match = quiet
    r = match.rounds[0]
    with PhysicsWorld(nav_world()) as physics:
        options = ReplayOptions(combat=False, bomb=True)
        result = replay_round(r, graph, options, physics=physics)
    players = player_metrics(r, result.trace())
    assert len(players) == 10 and set(players["side"]) == {"T", "CT"}
    assert players["mean_dist"].median() < 0.3
