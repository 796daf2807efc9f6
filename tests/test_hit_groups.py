"""The hit-group model on planted distributions, and the rules-grounded model on real hits."""

from __future__ import annotations

from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pandas as pd
import pytest
from studies import study

from decoy_cli.damage.hit_groups import GROUPS, HitGroupModel
from decoy_cli.damage.rules import shot_damage
from decoy_cli.esta import read_match

EVENTS = (
    Path(__file__).resolve().parents[1].parent
    / "shared"
    / "data"
    / "esta_dust2_events"
    / "og-navi-blast2020-r01-18.json.xz"
)
RULES = study("_damage_rules")
evaluate_rules = RULES.evaluate_rules
_victim_state = RULES._victim_state
PLANTED = np.array([0.2, 0.0, 0.5, 0.15, 0.1, 0.05])


def planted_hits(rng: np.random.Generator, weapon: str, n: int) -> tuple[list, list, list]:
    groups = [GROUPS[i] for i in rng.choice(len(GROUPS), size=n, p=PLANTED)]
    return [weapon] * n, list(rng.uniform(100, 1400, size=n)), groups


def test_sampled_frequencies_follow_a_planted_distribution() -> None:
    rng = np.random.default_rng(41)
    model = HitGroupModel.fit(*planted_hits(rng, "AK-47", 4000))
    drawn = model.sample(rng, ["AK-47"] * 20000, [600.0] * 20000)
    shares = pd.Series(drawn).value_counts(normalize=True).reindex(GROUPS, fill_value=0.0)
    assert np.abs(shares.to_numpy() - PLANTED).max() < 0.02
    assert model.probabilities("AK-47", 600.0).sum() == pytest.approx(1.0)


def test_a_rare_weapon_takes_its_class_shape_and_unknown_ones_all_weapons() -> None:
    rng = np.random.default_rng(42)
    weapons, distances, groups = planted_hits(rng, "AK-47", 3000)
    weapons += ["Galil AR"]  # one hit of another rifle, in the leg
    distances += [600.0]
    groups += ["LeftLeg"]
    model = HitGroupModel.fit(weapons, distances, groups)
    galil = model.probabilities("Galil AR", 600.0)
    assert galil[GROUPS.index("Chest")] > 0.4  # the rifles' shape, not its single leg hit
    assert galil[GROUPS.index("Leg")] < 0.2
    unknown = model.probabilities("Negev", 600.0)
    assert unknown[GROUPS.index("Chest")] > 0.4 and (unknown > 0).all()
    again = HitGroupModel.from_json(model.to_json())
    assert np.array_equal(again.probabilities("Galil AR", 600.0), galil)
    with pytest.raises(ValueError, match="other groups"):
        HitGroupModel.from_json('{"groups": ["Head"], "distance_bands_u": []}')


def test_events_made_by_the_rules_are_reproduced() -> None:
    # Rounds whose hits follow the rules exactly and a planted group distribution: the model's
    # damage matches per cell and its groups the planted shares.
    rng = np.random.default_rng(43)
    rounds = []
    for number in range(1, 21):
        weapons, distances, groups = planted_hits(rng, "M4A4", 40)
        rows = []
        for weapon, distance, group in zip(weapons, distances, groups, strict=True):
            hit = shot_damage(weapon, group, distance, armor=100, helmet=True)
            rows.append(
                {
                    # the columns the reader gives every damage row
                    "tick": 1000 + 64 * len(rows),
                    "attackerSteamID": 1,
                    "attackerName": "a",
                    "victimSteamID": 2,
                    "victimName": "v",
                    "weaponClass": "Rifle",
                    "hpDamageTaken": hit.health,
                    "attackerSide": "T",
                    "victimSide": "CT",
                    "isFriendlyFire": False,
                    "weapon": weapon,
                    "hitGroup": group,
                    "distance": distance,
                    "hpDamage": hit.health,
                    "armorDamage": max(hit.armor, 1) if group != "Leg" else 0,
                }
            )
        damages = pd.DataFrame(rows)
        rounds.append(
            SimpleNamespace(
                match_id="m", round_num=number, damages=damages, buy_types={"CT": "Full Buy"}
            )
        )
    result = evaluate_rules(rounds, seed=0)  # type: ignore[arg-type]
    assert result.hits == 800 and result.rounds == 20
    assert result.mean_wasserstein_hp < 1.0
    (row,) = result.group_tv.itertuples()
    assert row.tv < 0.05


@pytest.mark.skipif(not EVENTS.is_file(), reason="needs ../shared/data/esta_dust2_events")
def test_the_real_hits_leave_rounds_out() -> None:
    result = evaluate_rules(read_match(EVENTS).rounds, seed=0)
    assert result.hits == 396 and result.rounds == 18
    assert len(result.fold_mean_wasserstein_hp) == 5
    assert result.mean_wasserstein_hp <= 5.0  # issue 13's target, half the paper's 9.87
    # every weapon with 30 or more hits; USP-S, with 32, only by its floor: a model exactly
    # right exceeds 0.15 on some deals of 32 hits
    for _, row in result.group_tv.iterrows():
        assert row["tv"] <= (0.15 if row["hits"] >= 60 else max(0.15, 2 * row["tv_floor"]))
    assert result.max_wasserstein_hp <= 10.0  # and no cell above 10 HP
    floors = result.cells["floor_hp"]
    assert (floors >= 0).all() and floors.mean() < 5.0


def test_what_a_real_hit_says_of_the_victims_armour() -> None:
    """A hit that costs armour says kevlar (and a helmet on the head); a head hit that costs
    none says no helmet, whatever the shares say."""
    shares = {"": (1.0, 1.0)}  # every victim armoured with a helmet unless a hit says otherwise
    rng = np.random.default_rng(0)

    def state(group: str, armour: int) -> tuple[bool, bool]:
        hit = pd.Series({"victim_buy": "", "group": group, "armorDamage": armour})
        return _victim_state(hit, shares, rng)

    assert state("Head", 5) == (True, True)
    assert state("Head", 0) == (True, False)
    assert state("Chest", 4) == (True, True)
    assert state("Chest", 0) == (False, False)
    assert state("Leg", 0) == (True, True)


@pytest.mark.skipif(not EVENTS.is_file(), reason="needs ../shared/data/esta_dust2_events")
def test_models_on_the_same_folds_of_real_damaging_steps() -> None:
    from decoy_cli.damage import SHIPPED_MODELS
    from decoy_cli.damage.model_folder import load_dog
    from decoy_cli.modeling.samples import build_samples
    from decoy_cli.modeling.train_options import DogLossWeights, TrainOptions

    folds = study("_damage_folds")
    samples, _ = build_samples([EVENTS])
    quick = folds.CvaeTraining(
        TrainOptions(epochs=3, batch_size=32, patience=2),
        DogLossWeights(),
        load_dog(SHIPPED_MODELS).spec,
    )
    rules, cvae, shipped = folds.compare_on_folds(
        read_match(EVENTS).rounds,
        samples,
        {"shipped": SHIPPED_MODELS},
        seed=0,
        draws=4,
        cvae=quick,
    )
    assert rules.name.startswith("rules") and shipped.name == "shipped"
    assert cvae.name == "project CVAE (trained per fold)"
    for scores in (rules, cvae, shipped):
        assert scores.cells > 0 and np.isfinite(scores.mean_wasserstein_hp)
        assert len(scores.fold_means) == folds.FOLDS
        assert set(scores.group_tv) == {"AK-47", "M4A4", "USP-S"}
        assert 0 <= scores.mean_floor_hp < scores.mean_wasserstein_hp
    # the game's rules beat the DOG trained on most of these very rounds
    assert rules.mean_wasserstein_hp < shipped.mean_wasserstein_hp


def test_hit_group_tv_on_hand_cases() -> None:
    from decoy_cli.modeling.scores import hit_group_tv

    weapons = np.array(["AK-47"] * 40 + ["AWP"] * 5, dtype=object)
    real = np.array([0] * 20 + [2] * 20 + [2] * 5)
    same = hit_group_tv(weapons, real, weapons, real)
    assert same == {"AK-47": 0.0}  # the AWP has too few samples
    generated = np.array([2] * 40 + [2] * 5)
    assert hit_group_tv(weapons, real, weapons, generated) == {"AK-47": 0.5}


@pytest.mark.skipif(not EVENTS.is_file(), reason="needs ../shared/data/esta_dust2_events")
def test_the_rules_of_each_fold_never_see_its_test_rounds(monkeypatch: pytest.MonkeyPatch) -> None:
    from decoy_cli.modeling.damage_rows import group_id
    from decoy_cli.modeling.samples import build_samples

    comparison = study("_damage_folds")
    seen: list[set[str]] = []
    real_fit = comparison.fit_rules

    def recording_fit(rounds):  # type: ignore[no-untyped-def]
        seen.append({group_id(r) for r in rounds})
        return real_fit(rounds)

    monkeypatch.setattr(comparison, "fit_rules", recording_fit)
    samples, _ = build_samples([EVENTS])
    rounds = read_match(EVENTS).rounds
    comparison.compare_on_folds(rounds, samples, {}, seed=0, draws=2)
    everything = {group_id(r) for r in rounds if r.damages is not None and len(r.damages)}
    held_out = [everything - fitted for fitted in seen]
    assert len(seen) == comparison.FOLDS and all(held_out)
    # the held-out rounds of the folds partition the rounds: each is a test round exactly once
    assert sum(len(h) for h in held_out) == len(set().union(*held_out))
