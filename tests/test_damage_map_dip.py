"""The DIP each map gets: the shipped choices decide hits by their own DIP on the maps it was
trained on and by the shipped map-independent DIP (models/any_map) elsewhere, and say so; a
user's model folder keeps one DIP for every map and warns off its maps. Built by hand from
DIPs that always or never fire, so which one decided is visible in the hits."""

from __future__ import annotations

import dataclasses
import json
import shutil
from pathlib import Path

import numpy as np
import pytest
import torch
from esta_fixtures import make_match, write_match
from test_damage_combat import batch, model_folder
from trained_nets import trained_like
from typer.testing import CliRunner

import decoy_cli.damage
from decoy_cli.cli import app
from decoy_cli.damage import load_damage_model, model_roles
from decoy_cli.damage.combat import LearnedDamage
from decoy_cli.damage.features import FeatureSpec
from decoy_cli.damage.model_folder import save_dip
from decoy_cli.damage.model_maps import ANY_MAP, dip_for_map, map_warnings
from decoy_cli.damage.networks import DipNet
from decoy_cli.damage.rules_model import RULES_FILE, RulesDamage

ROOT = Path(__file__).resolve().parents[1]
WIDE = {"COLUMNS": "240"}
ARMED = ["AK-47"] * 12


def never_firing_dip(folder: Path, maps: list[str]) -> Path:
    """A relative-feature DIP that says 'no hit' for every pair (logit -20), trained on `maps`."""
    dip = trained_like(DipNet(), 5)
    with torch.no_grad():
        dip.classifier[4].weight.zero_()
        dip.classifier[4].bias.fill_(-20.0)
    return save_dip(folder, dip, FeatureSpec(units="relative"), 0.5, {"maps": maps})


@pytest.fixture
def shipped(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Path:
    """Shipped models whose own DIP (de_dust2) always fires and whose map-independent DIP
    (de_dust2 and de_ancient) never does, with the repository's rules.json."""
    folder = model_folder(tmp_path / "models", fire=True)
    for kind in ("dip", "dog"):
        path = folder / f"{kind}.json"
        data = json.loads(path.read_text())
        data["metadata"]["maps"] = ["de_dust2"]
        path.write_text(json.dumps(data))
    shutil.copy(ROOT / "models" / RULES_FILE, folder / RULES_FILE)
    never_firing_dip(folder / ANY_MAP, ["de_ancient", "de_dust2"])
    monkeypatch.setattr(decoy_cli.damage, "SHIPPED_MODELS", folder)
    return folder


def on_map(name: str):
    return dataclasses.replace(batch(12, weapons=ARMED), map_name=name)


@pytest.mark.parametrize("choice", ["rules", "shipped"])
def test_the_shipped_choices_decide_by_the_dip_of_the_map(shipped: Path, choice: str) -> None:
    model = load_damage_model(choice)
    assert isinstance(model, RulesDamage if choice == "rules" else LearnedDamage)
    rng = np.random.default_rng(0)
    assert model(on_map("de_dust2"), rng).hit.all()  # the shipped DIP fires
    for elsewhere in ("de_ancient", "de_nuke"):  # the map-independent one never does
        result = model(on_map(elsewhere), rng)
        assert not result.hit.any() and not result.damage.any()
    unarmed = dataclasses.replace(on_map("de_dust2"), attacker_weapon=np.full(12, "", dtype=object))
    assert not model(unarmed, rng).hit.any()  # a DIP that always fires: no weapon, no hit
    assert dip_for_map(choice, "de_dust2").folder == shipped
    assert dip_for_map(choice, "de_ancient").folder == shipped / ANY_MAP


def test_a_model_folder_keeps_its_dip_on_every_map(shipped: Path, tmp_path: Path) -> None:
    user = shutil.copytree(shipped, tmp_path / "mine")
    model = load_damage_model(str(user))
    assert model is not None
    assert model(on_map("de_ancient"), np.random.default_rng(0)).hit.all()
    assert not dip_for_map(str(user), "de_ancient").fallback
    (line, dog) = map_warnings(str(user), ["de_ancient"])
    assert "DIP (who hits)" in line and "trained on de_dust2 only, not on de_ancient" in line
    assert "DOG" in dog
    assert model_roles(str(user), "de_ancient")["hits"] == f"the DIP of {user}"


def test_the_fallback_is_named_in_warnings_and_roles(shipped: Path) -> None:
    assert map_warnings("rules", ["de_dust2"]) == []
    assert model_roles("rules", "de_dust2")["hits"] == "the DIP of the shipped models"
    stand_in = "the map-independent DIP of the shipped models (any_map)"
    assert model_roles("rules", "de_ancient")["hits"] == stand_in
    (ancient,) = map_warnings("rules", ["de_ancient"])
    assert ancient.startswith(f"hits on de_ancient are decided by {stand_in}")
    assert "trained on de_dust2 only" in ancient and "trained on de_ancient, de_dust2" in ancient
    nuke = map_warnings("rules", ["de_nuke"])
    assert nuke[0].startswith(f"hits on de_nuke are decided by {stand_in}")
    assert nuke[1] == f"{stand_in} never saw de_nuke: its hits there were not measured"
    assert "rules.json" in nuke[2] and "not on de_nuke" in nuke[2]
    # shipped: the DOG still warns off de_dust2, the DIP no longer does
    lines = map_warnings("shipped", ["de_ancient", "de_dust2"])
    assert len(lines) == 2 and "DOG (how much damage)" in lines[1]
    assert not any("DIP (who hits)" in line for line in lines)


def test_without_the_map_independent_dip_the_shipped_one_decides(shipped: Path) -> None:
    shutil.rmtree(shipped / ANY_MAP)
    model = load_damage_model("rules")
    assert model is not None and model(on_map("de_ancient"), np.random.default_rng(0)).hit.all()
    (line,) = map_warnings("rules", ["de_ancient"])
    assert line.startswith("the DIP (who hits) of --models rules was trained on de_dust2 only")


def test_the_evaluation_report_names_the_dip_of_its_map(shipped: Path) -> None:
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
        for name in ("de_dust2", "de_ancient")
    }
    assert lines["de_dust2"]["hits decided by"] == "the DIP of the shipped models"
    assert "model warnings" not in lines["de_dust2"]
    assert lines["de_ancient"]["hits decided by"].startswith("the map-independent DIP")
    assert lines["de_ancient"]["model warnings"].startswith("hits on de_ancient are decided")


def test_models_evaluate_scores_each_map_with_its_dip(tmp_path: Path) -> None:
    """The repository's shipped models on the fixture match as de_dust2 and as de_ancient:
    each map scored by its own DIP, at that DIP's threshold, and named."""
    if not (ROOT / "models" / ANY_MAP / "dip.json").is_file():
        pytest.skip("the map-independent DIP is not in models/")
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
    thresholds = {
        name: json.loads((folder / "dip.json").read_text())["threshold"]
        for name, folder in (
            ("de_dust2", ROOT / "models"),
            ("de_ancient", ROOT / "models" / ANY_MAP),
        )
    }
    assert thresholds["de_dust2"] != thresholds["de_ancient"]
    for name, threshold in thresholds.items():
        assert report["dip_by_map"][name]["threshold"] == pytest.approx(threshold)
        assert report["dip_by_map"][name]["positives"] == 2
    assert report["dip_of_map"] == {
        "de_ancient": "the map-independent DIP of the shipped models (any_map)",
        "de_dust2": "the DIP of the shipped models",
    }
    assert "DIP on de_ancient (the map-independent DIP of the shipped models" in result.output
    assert "DIP on de_dust2 (the DIP of the shipped models, threshold" in result.output
    assert "hits on de_ancient are decided by the map-independent DIP" in result.output
