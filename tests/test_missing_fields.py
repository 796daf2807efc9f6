"""Fields the game needs and the data lacks: filled by rule and named, or an error; what frames
and events contradict; the two death protocols; the kill-level metrics, checked by hand."""

from __future__ import annotations

import csv
import json
from pathlib import Path

import numpy as np
import pytest
from bomb_scenarios import site_a_walk
from both_teams import BothTeams, Mate, site_node
from typer.testing import CliRunner

from decoy_cli.cli import app
from decoy_cli.csgo import TICK_RATE
from decoy_cli.errors import EstaError
from decoy_cli.esta import Round, read_match
from decoy_cli.metrics.kills import kill_row, kill_table
from decoy_cli.replay.deaths import data_deaths
from decoy_cli.replay.missing import contradictions, fill_missing, lacking
from decoy_cli.replay.replayer import ReplayOptions, replay_round
from decoy_cli.sim.combat import CombatBatch, DamageResult
from decoy_cli.sim.rules import RulesConfig, SiteZones
from decoy_cli.waypoints.build import builtin_graph
from decoy_cli.weapons import FIREARMS


def read(doc: BothTeams, tmp_path: Path, name: str = "m.json") -> Round:
    return read_match(doc.write(tmp_path / name)).rounds[0]


def zones() -> SiteZones:
    return SiteZones.from_graph(builtin_graph())


def standing(name: str, side: str, region: str, k: int = 0, **kw: object) -> Mate:
    return Mate(name, side, [site_node(region, k)], **kw)  # type: ignore[arg-type]


def gunfight(round_num: int = 5) -> BothTeams:
    """t1 kills ct1 with an AK-47 and ct2 with a Desert Eagle; ct3 kills t3 with a USP-S."""
    return BothTeams(
        frames=12,
        round_num=round_num,
        players=[
            standing("t1", "T", "t_spawn", 0),
            standing("t2", "T", "t_spawn", 5),
            standing("t3", "T", "t_spawn", 10, dead_from=6),
            standing("ct1", "CT", "ct_spawn", 0, dead_from=4),
            standing("ct2", "CT", "ct_spawn", 5, dead_from=8),
            standing("ct3", "CT", "ct_spawn", 10),
        ],
        kills=[
            (3.5, "t1", "ct1", "AK-47"),
            (5.5, "ct3", "t3", "USP-S"),
            (7.5, "t1", "ct2", "Desert Eagle"),
        ],
    )


def test_weapons_armour_and_kits_are_filled_by_the_rules_and_named(tmp_path: Path) -> None:
    round_ = read(gunfight(), tmp_path)
    filled = fill_missing(round_, zones(), RulesConfig(), "infer")
    weapon = {p.name: filled.round.weapon[i] for i, p in enumerate(round_.players)}
    # t1: each frame holds the weapon of his next kill (frames 0-3 before the AK kill at 3.5 s)
    assert list(weapon["t1"]) == ["AK-47"] * 4 + ["Desert Eagle"] * 8
    # t2, no kill: the T side's kills were mostly with bought weapons -> its most used rifle
    assert set(weapon["t2"]) == {"AK-47"}
    # ct1, no kill: the CT side's only kill was with a pistol -> the CT pistol
    assert set(weapon["ct1"]) == {"USP-S"}
    armor = {p.name: filled.round.armor[i] for i, p in enumerate(round_.players)}
    kit = {p.name: filled.round.has_defuser[i] for i, p in enumerate(round_.players)}
    assert set(armor["t1"]) == {100} and filled.round.helmet[0].all()  # a buy
    assert set(armor["ct1"]) == {0} and not kit["ct1"].any()  # an eco
    notes = " | ".join(filled.notes)
    assert "weapon in hand (t1, ct3): its own kills' weapons" in notes
    assert "(t2, t3): AK-47: the T side's kills were mostly with bought weapons" in notes
    assert "(ct1, ct2): USP-S: the CT side's kills were mostly with pistols" in notes
    assert "no armour (an eco)" in notes and "vest and helmet (a buy)" in notes


@pytest.mark.parametrize(
    ("round_num", "weapon", "armor"), [(1, "Glock-18", 100), (5, "AK-47", 100)]
)
def test_without_kills_the_rounds_type_decides(
    tmp_path: Path, round_num: int, weapon: str, armor: int
) -> None:
    doc = gunfight(round_num)
    doc.kills = []
    doc.players = [Mate(p.name, p.side, p.nodes) for p in doc.players]  # nobody dies
    filled = fill_missing(read(doc, tmp_path), zones(), RulesConfig(), "infer")
    assert set(filled.round.weapon[0]) == {weapon}
    assert set(filled.round.armor[0]) == {armor}
    assert bool(filled.round.helmet[0].any()) is (round_num != 1)  # a vest only in a pistol round
    why = "a pistol round" if round_num == 1 else "the T side's usual rifle"
    assert f"weapon in hand (t1, t2, t3): {weapon}: {why}" in filled.notes


def test_missing_fields_as_an_error_fail_the_round(tmp_path: Path) -> None:
    round_ = read(gunfight(), tmp_path)
    with pytest.raises(EstaError, match=r"lacks what the game needs.*weapon in hand"):
        replay_round(round_, builtin_graph(), ReplayOptions(combat=False, missing="error"))


def planting(site_named: str = "A") -> BothTeams:
    """t1 walks into bomb site A and plants at 16 s (standing still from frame 13); t2 stands
    in T spawn; a CT in CT spawn. The data names no planter."""
    walk, _ = site_a_walk()
    return BothTeams(
        frames=22,
        players=[
            Mate("t1", "T", walk),
            standing("t2", "T", "t_spawn"),
            standing("ct1", "CT", "ct_spawn"),
        ],
        plant=(16.0, site_named),
        winner="T",
        reason="TargetBombed",
    )


def test_the_planter_is_the_t_standing_in_the_site_and_the_replay_plants(tmp_path: Path) -> None:
    round_ = read(planting(), tmp_path)
    filled = fill_missing(round_, zones(), RulesConfig(), "infer")
    t1 = [p.name for p in round_.players].index("t1")
    assert filled.round.has_bomb[t1, :16].all() and not filled.round.has_bomb[t1, 16:].any()
    assert any(
        "bomb carrier and planter (t1)" in note and "in site A" in note for note in filled.notes
    )
    result = replay_round(round_, builtin_graph(), ReplayOptions(combat=False))
    row = result.bomb_row()
    assert row is not None and row["plant_data"] and row["plant_replay"]
    assert (
        abs(row["plant_time_error_s"]) < 0.1
        and row["plant_site_data"] == row["plant_site_replay"] == "A"
    )
    assert any("bomb carrier and planter (t1)" in note for note in result.inferred)


def test_a_site_the_data_names_where_no_t_stood_gives_way_and_is_named(tmp_path: Path) -> None:
    round_ = read(planting(site_named="B"), tmp_path)
    filled = fill_missing(round_, zones(), RulesConfig(), "infer")
    (note,) = [n for n in filled.notes if n.startswith("bomb carrier")]
    assert "the data names site B, where no T stood: site A kept" in note
    assert list(filled.round.bomb_events["bombSite"]) == ["A"]


def test_a_defused_round_gets_its_defuser_and_the_replay_defuses(tmp_path: Path) -> None:
    doc = planting()
    walk, _ = site_a_walk()
    doc.frames = 36
    doc.players[0].dead_from = 24
    doc.players.append(Mate("ct2", "CT", [walk[0]] * 10 + walk))  # reaches the bomb by frame 23
    doc.kills = [(23.5, "ct2", "t1", "M4A1")]
    doc.winner, doc.reason, doc.end_s = "CT", "BombDefused", 35.0
    round_ = read(doc, tmp_path)
    filled = fill_missing(round_, zones(), RulesConfig(), "infer")
    events = filled.round.bomb_events
    starts = events[events["bombAction"] == "defuse_start"]
    assert list(starts["playerName"]) == ["ct2"]  # the CT alive at the end nearest the bomb
    assert float(starts["seconds"].iloc[0]) == pytest.approx(30.0)  # 5 s: a rifle buys a kit
    assert any(n.startswith("defuse (ct2)") and "with a kit" in n for n in filled.notes)
    result = replay_round(round_, builtin_graph(), ReplayOptions(combat=False))
    assert result.outcome is not None and result.outcome.reason == "BombDefused"
    row = result.bomb_row()
    assert row is not None and row["defuse_replay"]


def test_what_frames_and_events_contradict_is_named(tmp_path: Path) -> None:
    doc = gunfight()
    doc.kills.append((2.0, "ghost", "t2", "AK-47"))  # a killer in no frame; t2 lives on
    doc.reason, doc.winner = "TerroristsWin", "T"  # yet ct3 is alive at the end
    found = contradictions(read(doc, tmp_path))
    assert "the kill at tick 1128 names ghost, in no frame" in found
    assert "t2 is alive at frame 3, after its kill" in found
    assert "the round ends TerroristsWin, yet ct3 of the CT side are alive at its end" in found
    doc = gunfight()
    doc.reason = "BombDefused"
    found = contradictions(read(doc, tmp_path, "b.json"))
    assert found == ("the round ends BombDefused, but the bomb was never planted",)


def test_a_plant_with_no_t_alive_is_named_and_replayed_without_a_planter(tmp_path: Path) -> None:
    """Every T dead from frame 9 on, yet the data plants at 10 s: named, and the replay runs
    with nobody inferred as the planter (with the Ts alive, t1 would be) rather than failing."""
    doc = gunfight()
    for mate in doc.players:
        if mate.side == "T":
            mate.dead_from = 9
    doc.plant = (10.0, "A")
    round_ = read(doc, tmp_path)
    assert "the bomb is planted with no T alive" in contradictions(round_)
    result = replay_round(round_, builtin_graph(), ReplayOptions(combat=False))
    assert "the bomb is planted with no T alive" in result.contradictions
    assert not [item for item in result.inferred if "planter" in item]


def test_the_datas_death_time_is_its_kill_and_the_killer_known(tmp_path: Path) -> None:
    round_ = read(gunfight(), tmp_path)
    result = replay_round(round_, builtin_graph(), ReplayOptions(combat=False, bomb=False))
    truth = data_deaths(round_, result.plan.plans)
    rows = {p.name: i for i, p in enumerate(round_.players)}
    assert truth.seconds[rows["ct1"]] == pytest.approx(3.5)  # not 4.0, the first dead frame
    assert truth.killer[rows["ct1"]] == rows["t1"]
    assert truth.killer[rows["t3"]] == rows["ct3"]
    assert np.isnan(truth.seconds[rows["t2"]])
    # scripted deaths (no shooting) happen at the kill's time, as the data's deaths
    deaths = {e.agent: e.tick / 60 for e in result.events if e.kind == "death"}
    assert deaths[rows["ct1"]] == pytest.approx(3.5, abs=2 / 60)  # the tick before it


class AlwaysHits:
    """Every visible attacker hits for 40 HP in the chest (a damage model for tests)."""

    def __call__(self, batch: CombatBatch, rng: np.random.Generator) -> DamageResult:
        k = len(batch)
        return DamageResult(np.full(k, 40), np.full(k, 2), np.ones(k, bool))


def facing_off() -> BothTeams:
    """A T and a CT a few waypoints apart in bomb site A, in sight; the data kills the CT at
    9.5 s (by the T) and nobody else."""
    a = builtin_graph().region_of("bombsite_a")
    return BothTeams(
        frames=12,
        players=[
            Mate("t1", "T", [int(a[0])]),
            Mate("ct1", "CT", [int(a[3])], dead_from=10),
        ],
        kills=[(9.5, "t1", "ct1", "AK-47")],
        winner="T",
        reason="TerroristsWin",
    )


@pytest.mark.parametrize("deaths", ["simulated", "data"])
def test_who_decides_deaths(tmp_path: Path, deaths: str) -> None:
    round_ = read(facing_off(), tmp_path)
    options = ReplayOptions(damage_model=AlwaysHits(), bomb=False, deaths=deaths)  # type: ignore[arg-type]
    result = replay_round(round_, builtin_graph(), options)
    hits = [e for e in result.events if e.kind == "damage"]
    assert hits, "the two see each other and shoot"
    killed = {e.other: e.tick / 60 for e in result.events if e.kind == "kill"}
    scripted = {e.agent: e.tick / 60 for e in result.events if e.kind == "death"}
    if deaths == "data":
        # wounded to 1 HP, never killed by the fight; the CT dies at its kill's time
        assert not killed and set(scripted) == {1}
        assert scripted[1] == pytest.approx(9.5, abs=2 / 60)
        assert result.recording.alive[:, 0].all() and result.recording.hp[:, 0].min() == 1
        assert result.recording.hp[:10, 1].min() == 1 and not result.recording.alive[10:, 1].any()
    else:
        # the fight kills both at once within three steps of 40 HP, long before 9.5 s
        assert set(killed) == {0, 1} and not scripted
        assert max(killed.values()) < 2.0


class NeverHits:
    """Nobody hits (a damage model for tests)."""

    def __call__(self, batch: CombatBatch, rng: np.random.Generator) -> DamageResult:
        k = len(batch)
        return DamageResult(np.zeros(k, np.int64), np.full(k, -1), np.zeros(k, bool))


@pytest.mark.parametrize("kill_s", [5.5, 9.5])  # the window ends within the data, or after it
def test_a_death_the_fight_misses_is_taken_from_the_data_after_the_window(
    tmp_path: Path, kill_s: float
) -> None:
    doc = facing_off()
    doc.kills = [(kill_s, "t1", "ct1", "AK-47")]
    doc.players[1].dead_from = int(kill_s) + 1
    round_ = read(doc, tmp_path)
    options = ReplayOptions(damage_model=NeverHits(), bomb=False)
    result = replay_round(round_, builtin_graph(), options)
    (death,) = [e for e in result.events if e.kind in ("death", "kill")]
    assert death.kind == "death" and death.agent == 1 and death.data["reason"] == "scripted"
    assert death.tick / 60 == pytest.approx(kill_s + 3.0, abs=2 / 60)
    assert result.outcome is not None and result.outcome.winner == "T"
    row = result.kill_row(round_)
    assert row["deaths_original"] == 1 and row["deaths_recalled"] == 0  # not by the fight


class GrazesWhenArmed:
    """Every visible attacker holding a firearm hits for 1 HP (nobody dies; a test model)."""

    def __call__(self, batch: CombatBatch, rng: np.random.Generator) -> DamageResult:
        armed = np.isin(batch.attacker_weapon, FIREARMS)
        return DamageResult(armed.astype(np.int64), np.where(armed, 2, -1), armed)


def test_a_player_past_his_real_death_is_a_target_and_shoots_nobody(tmp_path: Path) -> None:
    doc = facing_off()
    doc.kills = [(5.5, "t1", "ct1", "AK-47")]
    doc.players[1].dead_from = 6
    round_ = read(doc, tmp_path)
    result = replay_round(round_, builtin_graph(), ReplayOptions(damage_model=GrazesWhenArmed()))
    hits = [(e.agent, e.tick / TICK_RATE) for e in result.events if e.kind == "damage"]
    by_ct = [s for agent, s in hits if agent == 1]
    by_t = [s for agent, s in hits if agent == 0]
    assert by_ct and max(by_ct) <= 5.5  # armed until the data's death, then not
    assert max(by_t) == 8.0  # the T hits him until he is taken out at 8.5 s
    (death,) = [e for e in result.events if e.kind == "death"]
    assert death.tick / TICK_RATE == pytest.approx(8.5, abs=2 / TICK_RATE)


def test_kill_row_by_hand() -> None:
    names = ["t1", "t2", "ct1", "ct2"]
    sides = ["T", "T", "CT", "CT"]
    nan = np.nan
    original = (np.array([nan, 20.0, 10.0, 30.0]), np.array([-1, 2, 0, 1]))
    # ct1 dies 2 s late by t1 (recalled, killer agrees); t2 12 s early (not recalled);
    # ct2 survives; t1 dies though he survived
    replay = (np.array([40.0, 8.0, 12.0, nan]), np.array([3, 2, 0, -1]), np.ones(4, bool))
    frames = 4
    alive_o = np.array([[1, 1, 1, 1], [1, 1, 0, 0], [1, 0, 0, 0], [1, 1, 1, 0]], bool)
    alive_r = np.array([[1, 1, 1, 0], [1, 0, 0, 0], [1, 1, 0, 0], [1, 1, 1, 1]], bool)
    row = kill_row(names, sides, original, replay, alive_o[:, :frames], alive_r)
    assert row["deaths_original"] == 3 and row["deaths_replay"] == 3
    assert row["deaths_recalled"] == 1 and row["killers_known"] == 3 and row["killers_agree"] == 1
    assert row["first_death_player_original"] == "ct1" and row["first_death_side_original"] == "CT"
    assert row["first_death_player_replay"] == "t2" and row["first_death_side_replay"] == "T"
    # alive counts T then CT per frame: original [2,2,1,1 | 2,1,1,0], replay [2,1,1,0 | 2,2,1,1]
    o = np.array([2, 2, 1, 1, 2, 1, 1, 0.0])
    r = np.array([2, 1, 1, 0, 2, 2, 1, 1.0])
    assert row["alive_corr"] == pytest.approx(np.corrcoef(o, r)[0, 1])
    assert row["alive_mad"] == pytest.approx(np.mean(np.abs(o - r)))
    # who is up: original (T-CT) 0, +1, 0, +1; replay 0, -1, 0, -1 -> same in frames 0 and 2
    assert row["advantage_agreement"] == pytest.approx(0.5)


def test_kill_table_pools_rounds() -> None:
    import pandas as pd

    rows = pd.DataFrame(
        [
            {
                "deaths_original": d,
                "deaths_recalled": r,
                "killers_known": d,
                "killers_agree": a,
                "first_death_side_original": "T",
                "first_death_side_replay": s,
                "first_death_player_original": "x",
                "first_death_player_replay": "x",
                "alive_corr": c,
                "alive_mad": 1.0,
                "advantage_agreement": 0.5,
            }
            for d, r, a, s, c in [(4, 2, 1, "T", 0.5), (6, 3, 3, "CT", 0.7)] * 6
        ]
    )
    table = kill_table(rows).set_index("metric")
    assert table.loc["death_recall", "value"] == pytest.approx(30 / 60)
    assert table.loc["killer_agreement", "value"] == pytest.approx(24 / 60)
    assert table.loc["first_death_side_agreement", "value"] == pytest.approx(0.5)
    assert table.loc["alive_corr", "value"] == pytest.approx(0.6)
    assert table.loc["death_recall", "low"] <= 0.5 <= table.loc["death_recall", "high"]


def test_shooting_with_nobody_armed_is_a_loud_warning(tmp_path: Path) -> None:
    doc = facing_off()
    for player in doc.players:
        player.weapon = "Knife"
    options = ReplayOptions(damage_model=AlwaysHits(), bomb=False)
    result = replay_round(read(doc, tmp_path), builtin_graph(), options)
    assert "shooting is on, but no player holds a firearm: nobody can shoot" in result.warnings


def _rows(path: Path) -> list[dict[str, str]]:
    with path.open(newline="") as handle:
        return list(csv.DictReader(handle))


def test_evaluate_names_what_it_inferred_and_the_protocol(tmp_path: Path) -> None:
    file = gunfight().write(tmp_path / "both.json")
    runner = CliRunner()
    out = tmp_path / "data"
    args = ["evaluate", str(file), "--no-bomb", "--workers", "0", "--no-figures", "--out", str(out)]
    result = runner.invoke(app, [*args, "--deaths", "data"], env={"COLUMNS": "200"})
    assert result.exit_code == 0, result.output
    assert "1 rounds lack fields the game needs" in result.stdout
    (row,) = _rows(out / "rounds.csv")
    assert "weapon in hand (t1, ct3): its own kills' weapons" in row["inferred"]
    assert row["deaths_original"] == "3" and row["deaths_replay"] == "3"
    summary = json.loads((out / "summary.json").read_text())
    assert summary["options"]["deaths"] == "data"
    assert summary["counts"]["rounds_with_inferred_fields"] == 1
    assert summary["inferred_by_round"]["both-teams:5"] == row["inferred"].split(" | ")
    combat = {r["metric"]: r for r in summary["combat"]}
    assert combat["outcome_agreement"]["paper"] == 0.91  # beside the paper's protocol only
    assert combat["death_recall"]["value"] == 0.0  # deaths scripted: none by the fight
    report = (out / "report.md").read_text()
    assert "## Fields the data lacks, filled by rule" in report
    assert "deaths from the data (the paper's protocol" in report
    assert "--deaths data" in summary["command"] and "--missing-fields infer" in summary["command"]
    # the default protocol: the paper's figures are not set beside it
    out = tmp_path / "simulated"
    args[-1] = str(out)
    result = runner.invoke(app, args, env={"COLUMNS": "200"})
    assert result.exit_code == 0, result.output
    summary = json.loads((out / "summary.json").read_text())
    assert summary["options"]["deaths"] == "simulated"
    assert all(r["paper"] is None for r in summary["combat"])
    # missing fields as an error: a recorded failure, one line, exit 1
    out = tmp_path / "error"
    args[-1] = str(out)
    args = [*args, "--no-combat", "--missing-fields", "error"]
    result = runner.invoke(app, args, env={"COLUMNS": "200"})
    assert result.exit_code == 1 and "Traceback" not in result.output
    (failure,) = _rows(out / "failures.csv")
    assert "lacks what the game needs" in failure["message"]


def test_info_says_what_a_file_lacks(tmp_path: Path) -> None:
    doc = planting()
    doc.reason, doc.winner = "BombDefused", "CT"
    file = doc.write(tmp_path / "lacking.json")
    assert lacking(read_match(file).rounds[0]) == ("weapon", "armour", "bomb carrier", "defuser")
    result = CliRunner().invoke(app, ["info", str(file)], env={"COLUMNS": "200"})
    assert result.exit_code == 0, result.output
    assert "weapon, armour, bomb carrier, defuser" in result.stdout
    assert "a replay fills them by rule" in result.stdout
