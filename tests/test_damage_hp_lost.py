"""Hits whose data records only the HP lost (no hit group, no raw damage), the HP-lost scores
by (weapon, distance band) cell, bullets per step by weapon, leave-matches-out folds, and the
maps a model knows. Expected values are derived by hand in each test."""

from __future__ import annotations

import dataclasses
import json
import shutil
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from esta_fixtures import make_match, write_match
from scipy.stats import wasserstein_distance
from typer.testing import CliRunner

from decoy_cli.cli import app
from decoy_cli.damage.bullet_counts import BulletCounts
from decoy_cli.damage.model_maps import map_warnings, trained_maps
from decoy_cli.modeling.hp_lost import band_labels, drawn_hp_lost, score_hp_lost
from decoy_cli.modeling.samples import build_samples
from decoy_cli.modeling.split import leave_matches_out

ROOT = Path(__file__).resolve().parents[1]
ANCIENT = ROOT.parent / "shared" / "data" / "events_ancient"
WIDE = {"COLUMNS": "200"}


def hp_lost_only(document: dict[str, Any]) -> dict[str, Any]:
    """The match with every damage row's hit group and raw damage removed, as events_ancient
    records them."""
    for round_ in document["gameRounds"]:
        for row in round_["damages"]:
            row["hitGroup"] = None
            row["hpDamage"] = None
    return document


def test_hits_without_hit_group_are_kept_on_their_hp_lost(tmp_path: Path) -> None:
    """Round 2's two firearm hits (27 and 120 HP raw, 27 and 100 HP lost) stay hits without
    hit group and raw damage; the world damage of round 3 is still left out."""
    path = write_match(tmp_path / "m.json.xz", hp_lost_only(make_match()))
    samples, stats = build_samples([path], mode="events")
    hits = samples.take(samples.hit)
    assert sorted(hits.hp_lost.tolist()) == [27.0, 100.0]
    assert np.isnan(hits.damage).all() and (hits.hit_group == -1).all()
    assert not samples.outcome_known.any()
    assert stats.partial == {"no hit group (scored on HP lost, over all hit groups)": 2}
    assert "unknown hit group" not in stats.excluded
    assert stats.excluded["world damage (no attacker)"] == 1


def test_hp_lost_cells_by_hand() -> None:
    """Twelve AK-47 steps at 300 u (band 0-500 u) lose 20 HP each; the model draws 30 HP on a
    victim of 25 HP (capped to 25) and 10 HP on the others: the cell's Wasserstein is the
    distance between twelve 20s and the drawn values; a cell of 3 M4A4 steps is below the
    10-sample minimum and stays out."""
    weapon = np.array(["AK-47"] * 12 + ["M4A4"] * 3, dtype=object)
    distance = np.array([300.0] * 12 + [1200.0] * 3)
    real = np.array([20.0] * 12 + [50.0] * 3)
    victim_hp = np.array([25] + [100] * 14)
    damage = np.tile(np.array([30.0] + [10.0] * 14), (2, 1))
    drawn = drawn_hp_lost(damage, victim_hp)
    assert drawn[0, 0] == 25.0 and drawn[0, 1] == 10.0
    scores = score_hp_lost(weapon, distance, real, drawn, min_cell=10)
    assert [(c["weapon"], c["part"], c["real"], c["generated"]) for c in scores.cells] == [
        ("AK-47", "0-500 u", 12, 24)
    ]
    expected = wasserstein_distance(real[:12], drawn[:, :12].ravel())
    assert scores.mean_wasserstein_hp == pytest.approx(expected)
    # both draws are identical: were the real steps drawn from the model, each draw matches
    assert scores.cells[0]["floor_hp"] == pytest.approx(0.0)
    assert scores.real_mean_hp == pytest.approx((12 * 20 + 3 * 50) / 15)
    assert scores.drawn_mean_hp == pytest.approx((25 + 14 * 10) / 15)
    assert band_labels(np.array([0.0, 499.9, 500.0, 1499.0, 1500.0])).tolist() == [
        "0-500 u", "0-500 u", "500-1000 u", "1000-1500 u", "1500+ u"
    ]  # fmt: skip


def test_bullets_per_step_by_weapon_pulled_toward_the_class() -> None:
    """Four rifle steps at 300 u: AK-47 one bullet twice, M4A4 one and two. All steps: (3, 1) /
    4; the Rifle class its counts (3, 1) pulled toward that with 5 pseudo-steps; the AK-47 its
    counts (2, 0) pulled toward the class's, and the AK-47 at 0-500 u the same counts toward
    the AK-47's."""
    counts = BulletCounts()
    for weapon, bullets in (("AK-47", 1), ("AK-47", 1), ("M4A4", 1), ("M4A4", 2)):
        counts.add(weapon, 300.0, bullets)
    every = np.array([3, 1] + [0] * 8) / 4
    rifle = (np.array([3, 1] + [0] * 8) + 5 * every) / (4 + 5)
    ak = (np.array([2, 0] + [0] * 8) + 5 * rifle) / (2 + 5)
    ak_near = (np.array([2, 0] + [0] * 8) + 5 * ak) / (2 + 5)
    np.testing.assert_allclose(counts.probabilities("AK-47", 300.0), ak_near)
    np.testing.assert_allclose(counts.probabilities("AK-47", 2000.0), ak)  # no far steps
    again = BulletCounts.from_dict(json.loads(json.dumps(counts.to_dict())))
    np.testing.assert_allclose(
        again.probabilities("M4A4", 300.0), counts.probabilities("M4A4", 300.0)
    )
    old = {"by_class": {"Rifle": [3.0, 1.0] + [0.0] * 8}, "every": [3.0, 1.0] + [0.0] * 8}
    np.testing.assert_allclose(BulletCounts.from_dict(old).probabilities("AK-47", 300.0), rifle)


def test_censored_bullet_counts_by_hand() -> None:
    """Two AK-47 steps at 300 u: one bullet that left the victim alive, two that killed it. All
    levels hold the same counts, so each pulls the hazard of "no further bullet" toward the one
    above with 5 pseudo-steps. At one bullet: 1 ended of 2 at risk; at two: none at risk (the
    kill says only "at least two"); the AK-47 was seen landing at most 2, so the rest ends
    there."""
    counts = BulletCounts(censored=True)
    counts.add("AK-47", 300.0, 1, killed=False)
    counts.add("AK-47", 300.0, 2, killed=True)
    hazard = np.ones(10)
    at_risk = np.array([2.0] + [0.0] * 9)
    ended = np.array([1.0] + [0.0] * 9)
    for _ in range(4):  # all steps, the Rifle class, the AK-47, the AK-47 at 0-500 u
        hazard = (ended + 5 * hazard) / (at_risk + 5)
    p_one = hazard[0]
    expected = np.array([p_one, 1 - p_one] + [0.0] * 8)
    np.testing.assert_allclose(counts.probabilities("AK-47", 300.0), expected)
    assert p_one < 1.0 and counts.probabilities("AK-47", 300.0)[1] > 0


def test_a_kill_hides_only_whether_one_more_bullet_would_land() -> None:
    """Desert Eagle steps at 300 u: one killed by its first bullet, one of one bullet and one of
    two that left their victims alive. The kill says only that at least one bullet lands, not
    whether a second would: at one bullet 1 step ended of the 2 whose fate there is known, at two
    the other (the most this weapon was seen to land). Each level pulls the hazard toward the
    one above with 5 pseudo-steps. Counting the kill at risk at one bullet (as if a second had
    landed) would give 1 of 3, and two bullets in more of the draws."""
    counts = BulletCounts(censored=True)
    counts.add("Desert Eagle", 300.0, 1, killed=True)
    counts.add("Desert Eagle", 300.0, 1, killed=False)
    counts.add("Desert Eagle", 300.0, 2, killed=False)
    hazard = 1.0
    for _ in range(4):  # all steps, the Pistols class, the Desert Eagle, at 0-500 u
        hazard = (1 + 5 * hazard) / (2 + 5)
    expected = [hazard, 1 - hazard] + [0.0] * 8
    np.testing.assert_allclose(counts.probabilities("Desert Eagle", 300.0), expected)


def test_leave_matches_out_folds() -> None:
    """Map A has two matches: one fold each. Map B has one match of 5 rounds: its rounds are
    dealt into folds of their own, every round in one fold."""
    from test_damage_samples import synthetic

    base = synthetic(groups=7, per_group=2, matches=1)
    maps = np.array(["de_a"] * 4 + ["de_b"] * 10, dtype=object)
    match = np.array(["m1"] * 2 + ["m2"] * 2 + ["m3"] * 10, dtype=object)
    group = np.array([f"g{k // 2}" for k in range(14)], dtype=object)
    samples = dataclasses.replace(base, map_name=maps, match=match, group=group)
    fold = leave_matches_out(samples, np.random.default_rng(0))
    assert fold[:4].tolist() == [0, 0, 1, 1]
    b = fold[4:]
    assert sorted(set(b.tolist())) == [2, 3, 4, 5, 6]  # 5 rounds in 5 folds of their own
    assert all(len(set(b[2 * k : 2 * k + 2].tolist())) == 1 for k in range(5))


def folder_with(tmp_path: Path, maps: list[str] | None) -> Path:
    """A copy of the shipped DIP and DOG whose metadata names `maps` (None: no maps key)."""
    folder = tmp_path / "models"
    folder.mkdir(parents=True)
    for kind in ("dip", "dog"):
        shutil.copy(ROOT / "models" / f"{kind}.pt", folder / f"{kind}.pt")
        data = json.loads((ROOT / "models" / f"{kind}.json").read_text())
        data["metadata"].pop("maps", None)
        if maps is not None:
            data["metadata"]["maps"] = maps
        (folder / f"{kind}.json").write_text(json.dumps(data))
    return folder


def test_a_model_used_on_other_maps_warns_naming_them(tmp_path: Path) -> None:
    folder = folder_with(tmp_path, ["de_dust2"])
    assert trained_maps(folder, "dip") == ["de_dust2"]
    assert map_warnings(str(folder), ["de_dust2"]) == []
    lines = map_warnings(str(folder), ["de_ancient", "de_dust2"])
    assert len(lines) == 2 and all("trained on de_dust2 only" in line for line in lines)
    assert all("not on de_ancient:" in line for line in lines)
    assert "DIP" in lines[0] and "DOG" in lines[1]
    silent = folder_with(tmp_path / "b", None)
    assert all("does not say which maps" in line for line in map_warnings(str(silent), ["x"]))
    assert map_warnings("none", ["de_ancient"]) == []
    # the shipped folder: DIP and rules of de_ancient and de_dust2, DOG of de_dust2
    assert trained_maps(ROOT / "models", "rules") == ["de_ancient", "de_dust2"]
    assert trained_maps(ROOT / "models", "dip") == ["de_ancient", "de_dust2"]
    assert map_warnings("rules", ["de_ancient"]) == []
    (dog_line,) = map_warnings("shipped", ["de_ancient"])
    assert "DOG" in dog_line and "not on de_ancient" in dog_line


@pytest.mark.skipif(not ANCIENT.is_dir(), reason="needs ../shared/data/events_ancient")
def test_models_evaluate_rules_on_hp_lost_only_data(tmp_path: Path) -> None:
    """The default model is evaluable on data without hit groups: per step and per hit, the
    partial rows counted, the DIP's map named."""
    out = tmp_path / "out"
    result = CliRunner().invoke(
        app, ["models", "evaluate", "rules", str(ANCIENT), "--out", str(out)], env=WIDE
    )
    assert result.exit_code == 0, result.output
    assert "no hit group (scored on HP lost, over all hit groups)" in result.output
    assert "warning" not in result.output  # the shipped DIP and rules know de_ancient
    report = json.loads((out / "metrics.json").read_text())
    assert report["damage_by"] == "rules" and set(report["hp_lost"]) == {"step", "hit"}
    step = report["hp_lost"]["step"]["de_ancient"]
    assert step["steps"] == report["dip"]["positives"]  # every damaging step scored
    assert report["dip_by_map"]["de_ancient"]["positives"] == step["steps"]
    assert report["dip_of_map"] == {"de_ancient": "the DIP of the shipped models"}
    assert "DIP on de_ancient (the DIP of the shipped models" in result.output
    # fitted on these very steps: as close to them as chance lets a model be, within 1 HP
    assert (
        step["mean_floor_hp"] > 0 and abs(step["mean_wasserstein_hp"] - step["mean_floor_hp"]) < 1
    )


def test_fold_comparison_labels_what_the_model_saw() -> None:
    """A model trained on rounds g0, g1 and validated on g2 has seen 3 of 7 rounds; on rounds it
    never saw it says so, naming its maps."""
    from studies import study
    from test_damage_samples import synthetic

    training_overlap = study("_damage_folds").training_overlap
    samples = synthetic(groups=7, per_group=2)
    groups = sorted(set(samples.group.tolist()))
    metadata = {"split": {"by": "round", "units": {"train": groups[:2], "val": groups[2:3]}}}
    assert training_overlap(metadata, samples) == "trained or validated on 3 of these 7 rounds"
    metadata = {"maps": ["de_dust2"], "split": {"by": "round", "units": {"train": ["other"]}}}
    assert training_overlap(metadata, samples) == "trained on none of these rounds (de_dust2)"
    assert training_overlap({}, samples) == "its training data unrecorded"


def test_hit_group_from_hp_lost_by_the_rules() -> None:
    """An AK-47 at 0 u on a victim without armour does 144 (head), 36 (neck, chest, arm), 45
    (stomach) or 27 (leg). A hit that left the victim alive after 45 HP was a stomach hit; one
    of 36 HP a neck, chest or arm hit in the prior's proportions; a kill of a 30-HP victim any
    group doing at least 30 (all but the leg); 10 HP no group (a shot through something); 33 HP,
    which no group gives within 1 HP, the groups by how close they come."""
    from decoy_cli.damage.hit_groups import GROUPS, HitGroupModel
    from decoy_cli.modeling.rules_fit import group_posterior

    prior = HitGroupModel.fit(["AK-47"] * 4, [0.0] * 4, ["Head", "Chest", "Chest", "Leg"])
    p = prior.probabilities("AK-47", 0.0)
    stomach = group_posterior(prior, "AK-47", 0.0, 45, 100, armored=False)
    assert stomach is not None and stomach.tolist() == [0, 0, 0, 1, 0, 0]
    body = group_posterior(prior, "AK-47", 0.0, 36, 100, armored=False)
    neck, chest, arm = (GROUPS.index(g) for g in ("Neck", "Chest", "Arm"))
    expected = np.zeros(6)
    expected[[neck, chest, arm]] = p[[neck, chest, arm]] / p[[neck, chest, arm]].sum()
    np.testing.assert_allclose(body, expected)
    kill = group_posterior(prior, "AK-47", 0.0, 30, 30, armored=False)
    assert kill is not None and kill[GROUPS.index("Leg")] == 0
    np.testing.assert_allclose(kill[:5], p[:5] / p[:5].sum())
    assert group_posterior(prior, "AK-47", 0.0, 10, 100, armored=False) is None
    # 33 HP: no group within 1 HP; weighed by closeness (15% of the rule damage per spread):
    # 36 (neck, chest, arm) is 0.56 spreads off, 27 (leg) 1.48, 45 (stomach) 1.78, 144 beyond 3
    near = group_posterior(prior, "AK-47", 0.0, 33, 100, armored=False)
    assert near is not None and near[GROUPS.index("Head")] == 0
    z = {"Chest": 3 / (0.15 * 36), "Leg": 6 / (0.15 * 27), "Stomach": 12 / (0.15 * 45)}
    weight = {g: p[GROUPS.index(g)] * np.exp(-0.5 * v * v) for g, v in z.items()}
    assert near[GROUPS.index("Chest")] / near[GROUPS.index("Leg")] == pytest.approx(
        weight["Chest"] / weight["Leg"]
    )
    assert near[GROUPS.index("Stomach")] / near[GROUPS.index("Chest")] == pytest.approx(
        weight["Stomach"] / weight["Chest"]
    )


def test_rules_file_keeps_bullets_of_hurt_victims(tmp_path: Path) -> None:
    """Steps on hurt victims draw from their own counts; a file without them uses `bullets`."""
    from decoy_cli.damage.hit_groups import HitGroupModel
    from decoy_cli.damage.rules_damage import RulesFile

    unhurt, hurt = BulletCounts(), BulletCounts()
    unhurt.add("AK-47", 300.0, 3)
    hurt.add("AK-47", 300.0, 1)
    rules = RulesFile(HitGroupModel(), unhurt, {}, bullets_hurt=hurt)
    rules.save(tmp_path)
    again = RulesFile.load(tmp_path)
    assert again.bullet_counts(100).probabilities("AK-47", 300.0)[2] == 1.0
    assert again.bullet_counts(99).probabilities("AK-47", 300.0)[0] == 1.0
    old = dataclasses.replace(rules, bullets_hurt=None)
    assert old.bullet_counts(40) is old.bullets


def test_hits_without_position_or_view_are_counted_by_reason(tmp_path: Path) -> None:
    """Round 2's first hit loses its victim's z, the second its attacker's view angle: neither
    becomes a sample, each is counted with its reason."""
    document = make_match()
    damages = document["gameRounds"][1]["damages"]
    damages[0]["victimZ"] = None
    damages[1]["attackerViewX"] = None
    path = write_match(tmp_path / "m.json.xz", document)
    samples, stats = build_samples([path], mode="events")
    assert stats.excluded["no attacker or victim position (x, y or z)"] == 1
    assert stats.excluded["no attacker or victim view angle"] == 1
    assert not samples.hit.any()


def test_models_evaluate_none_is_one_error_line(tmp_path: Path) -> None:
    path = write_match(tmp_path / "m.json.xz", make_match())
    result = CliRunner().invoke(app, ["models", "evaluate", "none", str(path)], env=WIDE)
    assert result.exit_code == 1
    assert result.output.strip().splitlines() == [
        "error: none: no models to evaluate (none turns shooting off)"
    ]


def test_models_evaluate_a_dip_alone(tmp_path: Path) -> None:
    """A folder with a DIP and neither DOG nor rules.json: its DIP is scored, the damage is
    not, and the output says so."""
    folder = tmp_path / "dip-only"
    folder.mkdir()
    for name in ("dip.pt", "dip.json"):
        shutil.copy(ROOT / "models" / name, folder / name)
    path = write_match(tmp_path / "m.json.xz", make_match())
    out = tmp_path / "out"
    args = ["models", "evaluate", str(folder), str(path), "--out", str(out), "--mode", "events"]
    result = CliRunner().invoke(app, args, env=WIDE)
    assert result.exit_code == 0, result.output
    assert "no DOG and no rules.json: the damage is not scored" in result.output
    report = json.loads((out / "metrics.json").read_text())
    assert report["dip"]["positives"] == 2 and report["hp_lost"] == {}


def test_the_evaluation_report_names_who_decides_hits_and_damage() -> None:
    """report.md and summary.json say which model decided the hits and which the damage, and
    warn when a model was not trained on the evaluated map."""
    from decoy_cli.evaluate.heat import HeatGrid
    from decoy_cli.evaluate.report import model_lines
    from decoy_cli.evaluate.settings import EvalSettings

    common = {"bomb": True, "mover": "kinematic", "seed": 0, "code": "c"}
    grid = HeatGrid.for_map("de_ancient")
    ancient = EvalSettings(
        map_name="de_ancient", combat=True, models="rules", grid=grid, models_fingerprint="f",
        **common,
    )  # fmt: skip
    lines = model_lines(ancient)
    assert lines["hits decided by"] == "the DIP of the shipped models"
    assert lines["damage decided by"].startswith("the game's damage rules")
    assert "model warnings" not in lines  # trained on de_ancient and de_dust2
    nuke = dataclasses.replace(ancient, map_name="de_nuke", grid=HeatGrid.for_map("de_nuke"))
    warned = model_lines(nuke)["model warnings"]
    assert "the DIP (who hits) of --models rules was trained on de_ancient, de_dust2 only" in warned
    assert model_lines(nuke)["hits decided by"] == "the DIP of the shipped models"
    off = dataclasses.replace(ancient, combat=False, models="none", models_fingerprint="")
    assert model_lines(off) == {
        "hits decided by": "none (no shooting)",
        "damage decided by": "none (no shooting)",
    }


def test_unidentifiable_players_are_counted_by_reason(tmp_path: Path) -> None:
    """Round 2's first hit loses its attacker's steamID and name, the second its victim's."""
    document = make_match()
    damages = document["gameRounds"][1]["damages"]
    damages[0]["attackerSteamID"] = damages[0]["attackerName"] = None
    damages[1]["victimSteamID"] = damages[1]["victimName"] = None
    path = write_match(tmp_path / "m.json.xz", document)
    _, stats = build_samples([path], mode="events")
    assert stats.excluded["attacker not identifiable (no steamID or name)"] == 1
    assert stats.excluded["victim not identifiable (no steamID or name)"] == 1


def test_paper_names_the_imported_folder(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """--models paper is the folder `paper`, else decoy-out/models/paper; with neither, one
    ModelError line says how to import it."""
    from decoy_cli.damage import resolve_models
    from decoy_cli.errors import ModelError

    monkeypatch.chdir(tmp_path)
    with pytest.raises(ModelError, match="import the paper's models first"):
        resolve_models("paper")
    (tmp_path / "decoy-out" / "models" / "paper").mkdir(parents=True)
    assert resolve_models("paper") == Path("decoy-out") / "models" / "paper"
    (tmp_path / "paper").mkdir()
    assert resolve_models("paper") == Path("paper")
