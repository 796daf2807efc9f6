"""The DIP of a `--models` choice decides hits on every map: the shipped one takes features that
name no place (models/dip.pt, trained on de_dust2 and de_ancient), and every choice warns, naming
the maps, where a part of it was not trained. Built by hand from DIPs that always fire, so which
one decided is visible in the hits."""

from __future__ import annotations

import dataclasses
import json
import shutil
from pathlib import Path

import numpy as np
import pytest
from esta_fixtures import make_match, write_match
from test_damage_combat import batch, model_folder
from typer.testing import CliRunner

import decoy_cli.damage
from decoy_cli.cli import app
from decoy_cli.damage import load_damage_model, model_roles
from decoy_cli.damage.combat import LearnedDamage
from decoy_cli.damage.model_maps import dip_of, map_warnings
from decoy_cli.damage.rules_damage import RULES_FILE, RulesDamage

ROOT = Path(__file__).resolve().parents[1]
WIDE = {"COLUMNS": "240"}
ARMED = ["AK-47"] * 12


@pytest.fixture
def shipped(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Path:
    """Shipped models whose DIP (de_ancient and de_dust2) always fires and whose DOG knows
    de_dust2 only, with the repository's rules.json (de_ancient and de_dust2)."""
    folder = model_folder(tmp_path / "models", fire=True)
    for kind, maps in (("dip", ["de_ancient", "de_dust2"]), ("dog", ["de_dust2"])):
        path = folder / f"{kind}.json"
        data = json.loads(path.read_text())
        data["metadata"]["maps"] = maps
        path.write_text(json.dumps(data))
    shutil.copy(ROOT / "models" / RULES_FILE, folder / RULES_FILE)
    monkeypatch.setattr(decoy_cli.damage, "SHIPPED_MODELS", folder)
    return folder


def on_map(name: str):
    return dataclasses.replace(batch(12, weapons=ARMED), map_name=name)


@pytest.mark.parametrize("choice", ["rules", "shipped"])
def test_the_shipped_choices_decide_by_one_dip_on_every_map(shipped: Path, choice: str) -> None:
    model = load_damage_model(choice)
    assert isinstance(model, RulesDamage if choice == "rules" else LearnedDamage)
    rng = np.random.default_rng(0)
    for where in ("de_dust2", "de_ancient", "de_nuke"):
        assert model(on_map(where), rng).hit.all()
    unarmed = dataclasses.replace(on_map("de_dust2"), attacker_weapon=np.full(12, "", dtype=object))
    assert not model(unarmed, rng).hit.any()  # a DIP that always fires: no weapon, no hit
    assert dip_of(choice).folder == shipped
    assert model_roles(choice)["hits"] == "the DIP of the shipped models"


def test_the_maps_a_part_never_saw_are_named(shipped: Path, tmp_path: Path) -> None:
    assert map_warnings("rules", ["de_dust2", "de_ancient"]) == []
    dip, rules = map_warnings("rules", ["de_nuke", "de_dust2"])
    assert dip.startswith("the DIP (who hits) of --models rules was trained on de_ancient, ")
    assert "not on de_nuke:" in dip and "rules.json" in rules and "not on de_nuke" in rules
    (dog,) = map_warnings("shipped", ["de_ancient", "de_dust2"])
    assert "DOG (how much damage)" in dog and "not on de_ancient" in dog
    user = shutil.copytree(shipped, tmp_path / "mine")
    assert model_roles(str(user))["hits"] == f"the DIP of {user}"
    assert len(map_warnings(str(user), ["de_nuke"])) == 2


def test_the_evaluation_report_names_the_dip_and_the_maps_it_never_saw(shipped: Path) -> None:
    from decoy_cli.evaluate.heat import HeatGrid
    from decoy_cli.evaluate.report import model_lines
    from decoy_cli.evaluate.settings import EvalSettings

    common = {"bomb": True, "mover": "kinematic", "seed": 0, "code": "c", "models": "rules"}
    lines = {
        name: model_lines(
            EvalSettings(
                map_name=name,
                combat=True,
                grid=HeatGrid.for_map(name),
                models_fingerprint="f",
                **common,
            )
        )
        for name in ("de_dust2", "de_nuke")
    }
    assert lines["de_dust2"]["hits decided by"] == "the DIP of the shipped models"
    assert "model warnings" not in lines["de_dust2"]
    assert lines["de_nuke"]["hits decided by"] == "the DIP of the shipped models"
    assert "not on de_nuke" in lines["de_nuke"]["model warnings"]


def test_models_evaluate_scores_each_map_with_the_one_dip(tmp_path: Path) -> None:
    """The repository's shipped models on the fixture match as de_dust2 and as de_ancient:
    both maps scored by the shipped DIP at the threshold the fight decides by, and named."""
    dust = write_match(tmp_path / "dust.json.xz", make_match())
    ancient = make_match()
    ancient["mapName"] = "de_ancient"
    ancient["matchID"] = "fixture-ancient"
    other = write_match(tmp_path / "ancient.json.xz", ancient)
    out = tmp_path / "out"
    args = ["models", "evaluate", "rules", str(dust), str(other), "--out", str(out)]
    result = CliRunner().invoke(app, [*args, "--mode", "events"], env=WIDE)
    assert result.exit_code == 0, result.output
    report = json.loads((out / "metrics.json").read_text())
    threshold = json.loads((ROOT / "models" / "dip_calibration.json").read_text())["threshold"]
    for name in ("de_dust2", "de_ancient"):
        assert report["dip_by_map"][name]["threshold"] == pytest.approx(threshold)
        assert report["dip_by_map"][name]["positives"] == 2
        assert report["dip_of_map"][name] == "the DIP of the shipped models"
        assert f"DIP on {name} (the DIP of the shipped models, threshold" in result.output
