"""The damage-model features: vocabularies, both unit systems by hand, fallbacks, bad input."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest
import torch

from decoy_cli.csgo import HAMMER_TO_M
from decoy_cli.damage.features import (
    HIT_GROUPS,
    MAPS,
    PAPER_SPEC,
    WEAPONS,
    Features,
    FeatureSpec,
    encode,
    map_index,
    weapon_index,
)
from decoy_cli.errors import ModelError
from decoy_cli.sim import combat
from decoy_cli.sim.combat import CombatBatch
from decoy_cli.weapons import WEAPONS as KNOWN_WEAPONS


def batch_of(
    attacker_u: list[tuple[float, float, float]],
    victim_u: list[tuple[float, float, float]],
    attacker_yaw: list[float],
    victim_yaw: list[float],
    hp: list[int],
    weapons: list[str],
    armor: list[int] | None = None,
    helmet: list[bool] | None = None,
    map_name: str = "de_dust2",
) -> CombatBatch:
    """A batch from positions in Hammer units (converted to metres, as the ESTA reader does)."""
    k = len(hp)
    a = np.asarray(attacker_u, float).reshape(k, 3) * HAMMER_TO_M
    v = np.asarray(victim_u, float).reshape(k, 3) * HAMMER_TO_M
    return CombatBatch(
        attacker=np.arange(k),
        victim=np.arange(k) + k,
        attacker_position=a,
        victim_position=v,
        attacker_yaw=np.asarray(attacker_yaw, float),
        victim_yaw=np.asarray(victim_yaw, float),
        attacker_hp=np.asarray(hp, np.int16),
        victim_hp=np.full(k, 100, np.int16),
        attacker_weapon=np.asarray(weapons, dtype=object),
        victim_armor=np.asarray(armor if armor is not None else [0] * k, np.int16),
        victim_helmet=np.asarray(helmet if helmet is not None else [False] * k, bool),
        map_name=map_name,
    )


def test_vocabularies_are_the_papers() -> None:
    assert MAPS == (
        "de_ancient",
        "de_dust2",
        "de_inferno",
        "de_train",
        "de_mirage",
        "de_nuke",
        "de_overpass",
        "de_vertigo",
    )
    assert len(WEAPONS) == 34 and list(WEAPONS) == sorted(WEAPONS)
    assert HIT_GROUPS == combat.HIT_GROUPS == ("Head", "Neck", "Chest", "Stomach", "Arm", "Leg")
    firearms = {
        name
        for name, (kind, _) in KNOWN_WEAPONS.items()
        if kind in ("Pistols", "SMG", "Rifle", "Heavy")
    }
    # Every firearm the project knows is in the vocabulary, and nothing the project does not.
    assert firearms == set(WEAPONS)
    outside = [name for name in KNOWN_WEAPONS if name not in firearms]
    assert "Zeus x27" in outside and "Knife" in outside and "HE Grenade" in outside
    assert weapon_index([*outside, "", "Banana"]).tolist() == [-1] * (len(outside) + 2)
    assert weapon_index(list(WEAPONS)).tolist() == list(range(34))


def test_hammer_features_by_hand() -> None:
    batch = batch_of(
        attacker_u=[(100.0, 200.0, 10.0), (0.0, 0.0, 0.0)],
        victim_u=[(100.0, 300.0, 10.0), (-300.0, 0.0, 400.0)],
        attacker_yaw=[90.0, 370.0],
        victim_yaw=[270.0, 180.0],
        hp=[57, 100],
        weapons=["AK-47", "USP-S"],
        armor=[100, 0],
        helmet=[True, False],
    )
    features = encode(batch, PAPER_SPEC)
    assert len(features) == 2
    expected = np.array(
        [
            # victim straight ahead (north, attacker looks north): bearing 0
            [100, 200, 10, 0.25, 100, 300, 10, 0.75, 0.57, 100, 0.0],
            # attacker looks at 370 = 10 degrees; the victim lies west (180 degrees) and 400 u
            # up: bearing 170 degrees, distance 500 u (3-4-5)
            [0, 0, 0, 10 / 360, -300, 0, 400, 0.5, 1.0, 500, 170 / 180],
        ]
    )
    np.testing.assert_allclose(features.coords, expected, rtol=1e-6, atol=1e-5)
    assert features.coords.dtype == np.float32
    assert features.map.tolist() == [[0, 1, 0, 0, 0, 0, 0, 0]] * 2
    assert features.weapon[0, WEAPONS.index("AK-47")] == 1 and features.weapon[0].sum() == 1
    assert features.weapon[1, WEAPONS.index("USP-S")] == 1 and features.weapon[1].sum() == 1
    assert features.armor.tolist() == [[1, 1], [0, 0]]  # [helmet, armor > 0], the paper's order


def test_bearing_wraps_to_minus_pi() -> None:
    # Victim straight behind an attacker looking east: the angle is pi, wrapped to -pi.
    batch = batch_of([(0, 0, 0)], [(-50, 0, 0)], [0.0], [0.0], [100], ["AWP"])
    for spec in (PAPER_SPEC, FeatureSpec()):
        assert encode(batch, spec).coords[0, 10] == -1.0


def paper_coords(batch: CombatBatch) -> np.ndarray:
    """An independent transcription of the paper's coordinate features (its dataset code, in
    torch, from raw Hammer units)."""
    rows = []
    for k in range(len(batch)):
        ax, ay, az = (batch.attacker_position[k] / HAMMER_TO_M).tolist()
        vx, vy, vz = (batch.victim_position[k] / HAMMER_TO_M).tolist()
        yaw, vyaw = float(batch.attacker_yaw[k]), float(batch.victim_yaw[k])
        distance = torch.sqrt(torch.tensor((ax - vx) ** 2 + (ay - vy) ** 2 + (az - vz) ** 2))
        angle = torch.atan2(torch.tensor(vy - ay), torch.tensor(vx - ax))
        relative = torch.remainder(angle - torch.tensor(yaw * np.pi / 180) + np.pi, 2 * np.pi)
        relative = (relative - np.pi) / np.pi
        hp = float(batch.attacker_hp[k]) / 100
        rows.append(
            [ax, ay, az, yaw / 360, vx, vy, vz, vyaw / 360, hp, distance.item(), relative.item()]
        )
    return np.array(rows)


def test_hammer_features_match_the_papers_formulas_on_random_pairs() -> None:
    rng = np.random.default_rng(3)
    k = 64
    batch = batch_of(
        attacker_u=rng.uniform(-3000, 3000, (k, 3)).tolist(),
        victim_u=rng.uniform(-3000, 3000, (k, 3)).tolist(),
        attacker_yaw=rng.uniform(0, 360, k).tolist(),
        victim_yaw=rng.uniform(0, 360, k).tolist(),
        hp=rng.integers(1, 101, k).tolist(),
        weapons=rng.choice(WEAPONS, k).tolist(),
    )
    np.testing.assert_allclose(
        encode(batch, PAPER_SPEC).coords, paper_coords(batch), rtol=2e-6, atol=2e-5
    )


def test_normalised_features_by_hand() -> None:
    spec = FeatureSpec(centre_m=(1.0, 2.0, 0.0), half_extent_m=(10.0, 20.0, 4.0))
    u = 1 / HAMMER_TO_M  # one metre in Hammer units
    batch = batch_of(
        attacker_u=[(11 * u, 2 * u, 2 * u)],
        victim_u=[(11 * u, 32 * u, 2 * u)],  # 30 m north of the attacker
        attacker_yaw=[270.0],  # looks south: the victim is behind
        victim_yaw=[270.0],  # looks south, at the attacker
        hp=[40],
        weapons=["Nova"],
    )
    coords = encode(batch, spec).coords[0]
    expected = [1.0, 0.0, 0.5, -0.5, 1.0, 1.5, 0.5, 0.0, 0.4, 30 / 50, -1.0]
    np.testing.assert_allclose(coords, expected, atol=1e-6)


def test_relative_features_by_hand_name_no_place_nor_map() -> None:
    """The same pair moved elsewhere, turned by the same angle for both, or on another map has
    the same relative features: distance, height difference, both bearings, HP."""
    spec = FeatureSpec(units="relative", centre_m=(1.0, 2.0, 0.0), half_extent_m=(10, 20, 4))
    u = 1 / HAMMER_TO_M
    here = batch_of(
        attacker_u=[(11 * u, 2 * u, 2 * u)],
        victim_u=[(11 * u, 32 * u, 4 * u)],  # 30 m north, 2 m higher
        attacker_yaw=[270.0],  # looks south: the victim is behind
        victim_yaw=[270.0],  # looks south, at the attacker
        hp=[40],
        weapons=["Nova"],
    )
    features = encode(here, spec)
    distance = np.hypot(30, 2) / 50
    expected = [0, 0, 2 / 4, 0, 0, 0, 0, 0.0, 0.4, distance, -1.0]
    np.testing.assert_allclose(features.coords[0], expected, atol=1e-6)
    assert not features.map.any()
    there = batch_of(
        attacker_u=[(-500 * u, 700 * u, -3 * u)],
        victim_u=[(-530 * u, 700 * u, -1 * u)],  # the same pair turned 90 degrees, elsewhere
        attacker_yaw=[0.0],
        victim_yaw=[0.0],
        hp=[40],
        weapons=["Nova"],
    )
    there = replace(there, map_name="de_ancient")
    np.testing.assert_allclose(encode(there, spec).coords, features.coords, atol=1e-6)
    assert FeatureSpec.from_json(spec.to_json()) == spec


def test_normalised_features_stay_near_unit_range_on_the_map() -> None:
    rng = np.random.default_rng(0)
    lo = np.array([-42.1, -22.5, -3.8]) / HAMMER_TO_M  # the built-in waypoints' box
    hi = np.array([34.2, 59.4, 3.1]) / HAMMER_TO_M
    k = 200
    batch = batch_of(
        attacker_u=rng.uniform(lo, hi, (k, 3)).tolist(),
        victim_u=rng.uniform(lo, hi, (k, 3)).tolist(),
        attacker_yaw=rng.uniform(-720, 720, k).tolist(),
        victim_yaw=rng.uniform(-720, 720, k).tolist(),
        hp=rng.integers(1, 101, k).tolist(),
        weapons=["M4A1"] * k,
    )
    coords = encode(batch, FeatureSpec()).coords
    assert np.all(np.abs(coords[:, [0, 1, 2, 4, 5, 6]]) <= 1.0)
    assert np.all((coords[:, [3, 7, 10]] >= -1.0) & (coords[:, [3, 7, 10]] < 1.0))
    assert np.all((coords[:, 9] >= 0) & (coords[:, 9] < 2.5))


def test_unknown_weapons_fall_back_to_a_zero_row() -> None:
    batch = batch_of(
        [(0, 0, 0)] * 4,
        [(100, 0, 0)] * 4,
        [0.0] * 4,
        [0.0] * 4,
        [100] * 4,
        ["Knife", "Zeus x27", "", "Glock-18"],
    )
    weapon = encode(batch, FeatureSpec()).weapon
    assert weapon[:3].sum() == 0
    assert weapon[3].argmax() == WEAPONS.index("Glock-18") and weapon[3].sum() == 1


def test_bad_input_is_a_model_error() -> None:
    good = batch_of([(0, 0, 0)], [(100, 0, 0)], [0.0], [0.0], [100], ["AK-47"])
    with pytest.raises(ModelError, match="no map 'de_cache'"):
        encode(
            batch_of([(0, 0, 0)], [(1, 0, 0)], [0], [0], [100], ["AK-47"], map_name="de_cache"),
            PAPER_SPEC,
        )
    with pytest.raises(ModelError, match="no map"):
        map_index("dust2")
    nan = batch_of([(math.nan, 0, 0)], [(100, 0, 0)], [0.0], [0.0], [100], ["AK-47"])
    with pytest.raises(ModelError, match="1 of 1 pairs have a NaN"):
        encode(nan, FeatureSpec())
    assert len(encode(good, FeatureSpec())) == 1


def test_an_empty_batch_has_empty_blocks() -> None:
    empty = batch_of(np.zeros((0, 3)).tolist(), np.zeros((0, 3)).tolist(), [], [], [], [])
    features = encode(empty, PAPER_SPEC)
    assert features.map.shape == (0, 8) and features.coords.shape == (0, 11)
    assert features.weapon.shape == (0, 34) and features.armor.shape == (0, 2)


def test_features_take_and_concat() -> None:
    rng = np.random.default_rng(1)
    k = 5
    batch = batch_of(
        rng.uniform(-500, 500, (k, 3)).tolist(),
        rng.uniform(-500, 500, (k, 3)).tolist(),
        rng.uniform(0, 360, k).tolist(),
        rng.uniform(0, 360, k).tolist(),
        [10, 20, 30, 40, 50],
        list(WEAPONS[:k]),
    )
    features = encode(batch, PAPER_SPEC)
    part = features.take(np.array([4, 1]))
    assert len(part) == 2 and part.coords[:, 8].tolist() == pytest.approx([0.5, 0.2])
    assert features.take(np.array([True, False, True, False, False])).coords[:, 8].tolist() == (
        pytest.approx([0.1, 0.3])
    )
    joined = Features.concat([features.take(slice(0, 2)), features.take(slice(2, 5))])
    for name in ("map", "coords", "weapon", "armor"):
        np.testing.assert_array_equal(getattr(joined, name), getattr(features, name))
    assert len(Features.concat([])) == 0
    with pytest.raises(ValueError, match="coords must be"):
        Features(features.map, features.coords[:, :10], features.weapon, features.armor)
    with pytest.raises(ValueError, match="different lengths"):
        Features(features.map[:2], features.coords, features.weapon, features.armor)


def test_feature_spec_json_round_trip_and_bad_specs() -> None:
    for spec in (FeatureSpec(), PAPER_SPEC, FeatureSpec(centre_m=(1, 2, 3), distance_scale_m=7)):
        assert FeatureSpec.from_json(spec.to_json()) == spec
    assert PAPER_SPEC.to_json() == {"units": "hammer"}
    with pytest.raises(ModelError, match="unknown feature units 'feet'"):
        FeatureSpec(units="feet")
    with pytest.raises(ModelError, match="half extent must be 3 positive"):
        FeatureSpec(half_extent_m=(1.0, 0.0, 1.0))
    with pytest.raises(ModelError, match="distance scale must be positive"):
        FeatureSpec(distance_scale_m=-1)
    with pytest.raises(ModelError, match="lacks centre_m"):
        FeatureSpec.from_json({"units": "normalised", "half_extent_m": [1, 1, 1]})
    with pytest.raises(ModelError, match="must be an object"):
        FeatureSpec.from_json(["hammer"])
    with pytest.raises(ModelError, match="bad feature spec"):
        FeatureSpec.from_json(
            {
                "units": "normalised",
                "centre_m": 5,
                "half_extent_m": [1, 1, 1],
                "distance_scale_m": 1,
            }
        )
