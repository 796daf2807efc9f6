"""`decoy models fit-rules`: the rules-grounded model's learned parts from real hits."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import pytest
from typer.testing import CliRunner

from decoy_cli.cli import app
from decoy_cli.damage import load_damage_model
from decoy_cli.damage.bullet_counts import ALL, MAX_BULLETS
from decoy_cli.damage.rules_damage import RulesDamage
from decoy_cli.errors import ModelError

runner = CliRunner()
ROOT = Path(__file__).resolve().parents[1]
EVENTS = ROOT.parent / "shared" / "data" / "esta_dust2_events"
ANCIENT = ROOT.parent / "shared" / "data" / "events_ancient"


@pytest.mark.skipif(
    not (EVENTS.is_dir() and ANCIENT.is_dir()),
    reason="needs ../shared/data/esta_dust2_events and ../shared/data/events_ancient",
)
def test_fit_rules_beside_a_dip_makes_a_rules_model(tmp_path: Path) -> None:
    folder = tmp_path / "rules"
    folder.mkdir()
    for name in ("dip.pt", "dip.json"):
        shutil.copy(ROOT / "models" / name, folder / name)
    result = runner.invoke(
        app, ["models", "fit-rules", str(folder), str(EVENTS), str(ANCIENT)], env={"COLUMNS": "300"}
    )
    assert result.exit_code == 0, result.output
    # hit groups from de_dust2's 396 hits and the de_ancient hits the rules explain; bullets
    # per step from the steps of both maps
    assert "396 firearm hits" in result.output and "1536 damaging steps" in result.output
    data = json.loads((folder / "rules.json").read_text())
    explained, left = data["provenance"]["hits_by_hp_lost"], data["provenance"]["hits_unexplained"]
    assert explained + left == 1835 and explained > 4 * left
    data = json.loads((folder / "rules.json").read_text())
    every = data["bullets"]["counts"][ALL]
    assert sum(every) > 0 and len(every) == MAX_BULLETS and data["bullets"]["censored"]
    # the shipped rules.json is this very fit
    shipped = json.loads((ROOT / "models" / "rules.json").read_text())
    assert data["bullets"] == shipped["bullets"]
    assert data["penetration"] == shipped["penetration"]
    assert data["penetration"]["hits"] == 396 and 0 < len(data["penetration"]["shares"]) < 396 / 5
    assert data["provenance"]["maps"] == ["de_ancient", "de_dust2"]
    assert isinstance(load_damage_model(str(folder)), RulesDamage)  # a DIP and rules, no DOG


def test_a_step_another_attacker_ends_counts_as_cut_short(tmp_path: Path) -> None:
    """Round 2 of the fixture (128 ticks: 64 ticks a step), its damages replaced: ct1 lands
    one bullet (27 HP) on unhurt t1 and, in the same 0.5 s step, ct2 finishes him (73 HP, on a
    victim then hurt): ct1's step was cut short by the death as much as ct2's, so both are
    censored (killed). ct1 hurts t2 (30 HP, unhurt before, alive after) and two steps later
    lands the rest (70 HP, on a hurt victim: censored too)."""
    from esta_fixtures import _damage, make_match, write_match

    from decoy_cli.esta import read_match
    from decoy_cli.modeling.rules_fit import fit_rules

    match = make_match()
    match["gameRounds"][1]["damages"] = [
        _damage(5070, "ct1", "t1", "M4A4", 27),
        _damage(5075, "ct2", "t1", "M4A4", 73),
        _damage(5100, "ct1", "t2", "M4A4", 30),
        _damage(5200, "ct1", "t2", "M4A4", 70),
    ]
    path = write_match(tmp_path / "m.json.xz", match)
    rules = fit_rules([r for r in read_match(path).rounds if r.round_num == 2])
    assert rules.bullets.counts[ALL][0] == 2 and rules.bullets.killed[ALL][0] == 1
    assert rules.bullets_hurt is not None and rules.bullets_hurt.censored
    assert rules.bullets_hurt.counts[ALL][0] == 2 and rules.bullets_hurt.killed[ALL][0] == 2


def test_damage_without_a_tick_ends_no_step(tmp_path: Path) -> None:
    """A row without a tick says nothing of when the victim lost that HP: ct1's one bullet
    (27 HP) on unhurt t1 stays a step he survived, though a world-damage row without a tick
    takes t1's other 73 HP."""
    from esta_fixtures import _damage, make_match, write_match

    from decoy_cli.esta import read_match
    from decoy_cli.modeling.rules_fit import fit_rules

    match = make_match()
    no_tick = _damage(5075, None, "t1", "World", 73) | {"tick": None}
    match["gameRounds"][1]["damages"] = [_damage(5070, "ct1", "t1", "M4A4", 27), no_tick]
    path = write_match(tmp_path / "m.json.xz", match)
    rules = fit_rules([r for r in read_match(path).rounds if r.round_num == 2])
    assert rules.bullets.counts[ALL][0] == 1 and rules.bullets.killed[ALL][0] == 0


def test_bad_folders_are_one_error_line(tmp_path: Path) -> None:
    result = runner.invoke(app, ["models", "fit-rules", str(tmp_path), str(tmp_path)])
    assert result.exit_code == 1 and "error: " in result.output
    assert "holds no dip.json" in result.output
    with_dog = runner.invoke(app, ["models", "fit-rules", str(ROOT / "models"), str(tmp_path)])
    assert with_dog.exit_code == 1 and "holds a DOG" in with_dog.output
    folder = tmp_path / "broken"
    folder.mkdir()
    for name in ("dip.pt", "dip.json"):
        shutil.copy(ROOT / "models" / name, folder / name)
    (folder / "rules.json").write_text("{not json")
    with pytest.raises(ModelError, match=r"rules\.json: not readable JSON"):
        load_damage_model(str(folder))
    (folder / "rules.json").write_text('{"hit_groups": {}, "bullets": {}, "provenance": "x"}')
    with pytest.raises(ModelError, match="not a rules file"):
        load_damage_model(str(folder))
    shipped = json.loads((ROOT / "models" / "rules.json").read_text())
    for through in ({"hits": 3, "shares": [0.5, 1.5]}, {"hits": 1, "shares": [0.5, 0.5]}):
        (folder / "rules.json").write_text(json.dumps(shipped | {"penetration": through}))
        with pytest.raises(ModelError, match="penetration shares"):
            load_damage_model(str(folder))
    # a rules.json from before penetration was learned: every path clear
    (folder / "rules.json").write_text(
        json.dumps({k: v for k, v in shipped.items() if k != "penetration"})
    )
    model = load_damage_model(str(folder))
    assert isinstance(model, RulesDamage) and model.rules.penetration.shares == []
