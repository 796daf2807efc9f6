"""The fight's operating point (decoy_cli/modeling/fight_threshold.py, `decoy models
fight-threshold`): the pairs of a hand-made round of both teams, the choice by hand, the command
end to end, and the shipped choice on the shared real rounds."""

from __future__ import annotations

import json
import re
import shutil
from pathlib import Path

import numpy as np
import pytest
from both_teams import BothTeams, Mate
from esta_fixtures import make_match, write_match
from typer.testing import CliRunner

from decoy_cli.cli import app
from decoy_cli.damage.combat import DipDecision
from decoy_cli.damage.model_folder import load_dip, save_dip
from decoy_cli.esta import read_match
from decoy_cli.modeling.fight_threshold import choose_fight_threshold, fight_pairs
from decoy_cli.waypoints.build import builtin_graph

runner = CliRunner()
WIDE = {"COLUMNS": "200"}
ROOT = Path(__file__).resolve().parents[1]
DATA = ROOT.parent / "shared" / "data"


def dip_alone(tmp_path: Path) -> Path:
    """A model folder holding a copy of the shipped DIP and nothing else."""
    folder = tmp_path / "models"
    folder.mkdir()
    for name in ("dip.pt", "dip.json"):
        shutil.copy(ROOT / "models" / name, folder / name)
    return folder


def facing_off() -> BothTeams:
    """A T and a CT in bomb site A, in sight of each other; the T kills the CT at 9.5 s."""
    a = builtin_graph().region_of("bombsite_a")
    return BothTeams(
        frames=12,
        players=[Mate("t1", "T", [int(a[0])]), Mate("ct1", "CT", [int(a[3])], dead_from=10)],
        kills=[(9.5, "t1", "ct1", "AK-47")],
        winner="T",
        reason="TerroristsWin",
    )


def test_the_pairs_are_players_with_one_enemy_in_sight_labelled_by_lost_hp(
    tmp_path: Path,
) -> None:
    """Frames 0-9 give both players as victims of the other (frame 10 has no enemy alive for
    t1, frame 11 no frame a second later); only ct1 at frame 9 loses HP within the second. Each
    attacker aims at his victim, as the fight's do, with the weapon the missing-field rules
    give (t1's kill: AK-47; ct1 none of his own: the CT side's usual rifle)."""
    round_ = read_match(facing_off().write(tmp_path / "m.json")).rounds[0]
    pairs = fight_pairs([round_], builtin_graph())
    names = [p.name for p in round_.players]
    victims = [names[v] for v in pairs.batch.victim]
    assert len(pairs.lost_hp) == 20 and victims.count("t1") == victims.count("ct1") == 10
    (lost,) = np.flatnonzero(pairs.lost_hp)
    assert victims[lost] == "ct1"
    assert sorted(set(pairs.batch.attacker_weapon)) == ["AK-47", "M4A1"]
    delta = pairs.batch.victim_position - pairs.batch.attacker_position
    facing = np.degrees(np.arctan2(delta[:, 1], delta[:, 0]))
    np.testing.assert_allclose(pairs.batch.attacker_yaw, facing)
    np.testing.assert_allclose(pairs.batch.victim_yaw, facing + 180.0)
    assert pairs.rounds == 1 and set(pairs.round_index) == {0}


def test_the_choice_is_the_best_f1_the_recall_allows() -> None:
    """F1 by hand: 1.0 for thresholds in (0.3, 0.85], 0.8 in (0.2, 0.3], 0.667 in (0.1, 0.2];
    the real damaging steps' recall stays at 3 of 5 up to 0.3."""
    probability = np.array([0.9, 0.85, 0.3, 0.2, 0.1])
    lost = np.array([True, True, False, False, False])
    damaging = {"de_x": np.array([0.5, 0.4, 0.3, 0.2, 0.1])}
    free = choose_fight_threshold(probability, lost, damaging, 0.12, min_recall=0.0)
    assert free.threshold == 0.35  # the lowest of the best
    held = choose_fight_threshold(probability, lost, damaging, 0.12, min_recall=0.6)
    assert held.threshold == 0.25
    row = next(r for r in held.rows if r["threshold"] == 0.35)
    assert row["f1"] == 1.0 and row["recall:de_x"] == 0.4 and not row["allowed"]
    own = choose_fight_threshold(probability, lost, damaging, 0.12, min_recall=1.0)
    assert own.threshold == 0.12  # only DIP's own and 0.05, 0.1 remain: it scores best


def test_recall_is_held_on_the_steps_dip_did_not_train_on() -> None:
    """Map A has a match DIP trained on and one it did not: its recall is held on the latter
    alone. Map B's only match was trained on: held on it, and named so. Split by round, the
    rounds name the steps. A DIP whose metadata names no split (imported, older) is held on
    every step, and says so."""
    import dataclasses

    from test_damage_samples import synthetic

    from decoy_cli.modeling.fight_threshold import _damaging_by_map
    from decoy_cli.modeling.provenance import seen_in

    base = synthetic(groups=6, per_group=2, matches=1)
    maps = np.array(["de_a"] * 8 + ["de_b"] * 4, dtype=object)
    match = np.array(["m1"] * 4 + ["m2"] * 4 + ["m3"] * 4, dtype=object)
    steps = dataclasses.replace(base, map_name=maps, match=match)

    def trained(split: object) -> np.ndarray | None:  # as DIP's metadata records its split
        return seen_in({"split": split}, steps, ("train",))

    by_match = trained({"by": "match", "units": {"train": ["m1", "m3"], "val": ["m2"]}})
    assert by_match is not None
    assert by_match.tolist() == [True] * 4 + [False] * 4 + [True] * 4
    parts = _damaging_by_map(steps, by_match)
    assert sorted(parts) == ["de_a held out (4)", "de_b trained on (4)"]
    assert parts["de_a held out (4)"].match.tolist() == ["m2"] * 4
    rounds = sorted(set(steps.group.tolist()))
    by_round = trained({"by": "round", "units": {"train": rounds[:1]}})
    assert by_round is not None and by_round.tolist() == [True] * 2 + [False] * 10
    for odd in (None, {"by": "matches", "units": {"train": ["m1"]}}, {"by": "match"}):
        assert trained(odd) is None
    assert sorted(_damaging_by_map(steps, None)) == ["de_a all steps (8)", "de_b all steps (4)"]


def test_the_command_writes_the_fights_threshold(tmp_path: Path) -> None:
    folder = dip_alone(tmp_path)
    rounds = facing_off().write(tmp_path / "both.json")
    events = write_match(tmp_path / "events.json.xz", make_match())
    result = runner.invoke(
        app, ["models", "fight-threshold", str(folder), str(rounds), str(events)], env=WIDE
    )
    assert result.exit_code == 0, result.output
    assert "chosen" in result.output and "recall de_dust2" in result.output
    written = json.loads((folder / "dip_calibration.json").read_text())
    assert written["kind"] == "none" and written["decision"] == "threshold"
    dip = load_dip(folder)
    assert dip.decision_threshold == written["threshold"]
    assert DipDecision(dip).threshold == written["threshold"]  # the fight decides by it


def _one_error_line(args: list[str]) -> str:
    result = runner.invoke(app, ["models", "fight-threshold", *args], env=WIDE)
    assert result.exit_code == 1, result.output
    assert result.output.startswith("error:") and len(result.output.strip().splitlines()) == 1
    return result.output


def test_what_the_command_cannot_choose_on_is_one_error_line(tmp_path: Path) -> None:
    folder = dip_alone(tmp_path)
    rounds = facing_off().write(tmp_path / "both.json")
    events_only = make_match()
    for round_ in events_only["gameRounds"]:
        round_["frames"] = []
    events = write_match(tmp_path / "events.json.xz", events_only)
    assert "no usable samples" in _one_error_line([str(folder), str(rounds)])  # no damage
    assert "both teams" in _one_error_line([str(folder), str(events)])
    assert "no such file" in _one_error_line([str(folder), str(tmp_path / "absent.json")])
    assert "dip.json" in _one_error_line([str(tmp_path), str(rounds), str(events)])
    assert not (folder / "dip_calibration.json").exists()


def test_a_new_dip_drops_the_calibration_fitted_for_the_one_it_replaces(tmp_path: Path) -> None:
    folder = tmp_path / "models"
    shutil.copytree(ROOT / "models", folder)
    dip = load_dip(folder)
    assert dip.calibration is not None
    save_dip(folder, dip.net, dip.spec, dip.threshold, dip.metadata)
    assert not (folder / "dip_calibration.json").exists()
    assert load_dip(folder).decision_threshold == dip.threshold


@pytest.mark.skipif(
    not (DATA / "cs2_dust2_both").is_dir() or not (DATA / "events_ancient").is_dir(),
    reason="needs ../shared/data/cs2_dust2_both, esta_dust2_events and events_ancient",
)
def test_the_shipped_threshold_is_what_the_command_chooses_on_the_real_rounds(
    tmp_path: Path,
) -> None:
    folder = dip_alone(tmp_path)
    both = DATA / "cs2_dust2_both" / "spirit-vs-falcons-m2-dust2-r01-12.json.xz"
    data = [both, DATA / "esta_dust2_events", DATA / "events_ancient"]
    result = runner.invoke(
        app, ["models", "fight-threshold", str(folder), *map(str, data)], env=WIDE
    )
    assert result.exit_code == 0, result.output
    shipped = json.loads((ROOT / "models" / "dip_calibration.json").read_text())
    assert json.loads((folder / "dip_calibration.json").read_text()) == shipped
    halves = re.search(r"alone: ([0-9.]+), ([0-9.]+)", " ".join(result.output.split()))
    assert halves is not None  # each half of the rounds alone chooses within one step of it
    assert all(abs(float(h) - shipped["threshold"]) <= 0.05 + 1e-9 for h in halves.groups())


@pytest.mark.skipif(
    not (DATA / "cs2_dust2_both").is_dir() or not (DATA / "events_ancient").is_dir(),
    reason="needs ../shared/data/cs2_dust2_both, esta_dust2_events and events_ancient",
)
def test_world_cs2_chooses_on_sight_in_cs2_s_world(tmp_path: Path) -> None:
    """`--world cs2`: the pairs are those in sight in CS2's de_dust2 world, not CS:GO's."""
    folder = dip_alone(tmp_path)
    both = DATA / "cs2_dust2_both" / "spirit-vs-falcons-m2-dust2-r01-12.json.xz"
    data = [both, DATA / "esta_dust2_events", DATA / "events_ancient"]
    rounds = read_match(both).rounds
    counts = {w: len(fight_pairs(rounds, builtin_graph(world=w)).lost_hp) for w in ("csgo", "cs2")}
    assert counts["csgo"] != counts["cs2"]
    result = runner.invoke(
        app,
        ["models", "fight-threshold", str(folder), *map(str, data), "--world", "cs2"],
        env=WIDE,
    )
    assert result.exit_code == 0, result.output
    assert f"{counts['cs2']} player-frames" in result.output
