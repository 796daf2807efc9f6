"""Training samples of the damage models (decoy_cli/modeling/samples.py), checked by hand on the
generated ESTA fixture (tests/esta_fixtures.py), plus the split, the balancing and the flash
events the reader gained for the events-only mode."""

from __future__ import annotations

import dataclasses
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from esta_fixtures import (
    CT_PLAYERS,
    ROUND2_TICKS,
    T_PLAYERS,
    TICK_RATE,
    _damage,
    expected_hammer_position,
    make_match,
    write_match,
)

from decoy_cli.csgo import HAMMER_TO_M
from decoy_cli.damage.features import FeatureSpec, map_index
from decoy_cli.errors import DecoyError
from decoy_cli.esta import Round, read_match
from decoy_cli.modeling.filled_views import (
    ATTACKER_DEVIATION_DEG,
    FILLED_NOTE,
    QUANTILES,
    VICTIM_DEVIATION_DEG,
    filled_views,
    hit_view_deviations,
)
from decoy_cli.modeling.samples import (
    Samples,
    SampleStats,
    balance,
    build_samples,
    split_samples,
)

DATA = Path(__file__).resolve().parents[1].parent / "shared" / "data"
EVENTS = DATA / "esta_dust2_events"


def metres(name: str, frame: int) -> np.ndarray:
    return np.array(expected_hammer_position(name, frame)) * HAMMER_TO_M


def write(tmp_path: Path, document: dict[str, Any], name: str = "m.json.xz") -> Path:
    return write_match(tmp_path / name, document)


def flash(tick: int, thrower: str, flashed: str) -> dict[str, Any]:
    """A flash row as awpy 1.x writes it (thrower = attacker, flashed = player)."""
    ids = dict(T_PLAYERS + CT_PLAYERS)
    tx, ty, tz = expected_hammer_position(thrower, 1)
    px, py, pz = expected_hammer_position(flashed, 1)
    return {
        "tick": tick,
        "seconds": 1.0,
        "clockTime": "01:54",
        "attackerSteamID": ids[thrower],
        "attackerName": thrower,
        "attackerTeam": "Team B",
        "attackerSide": "CT",
        "attackerX": tx,
        "attackerY": ty,
        "attackerZ": tz,
        "attackerViewX": 80.0,
        "attackerViewY": 0.0,
        "playerSteamID": ids[flashed],
        "playerName": flashed,
        "playerTeam": "Team A",
        "playerSide": "T",
        "playerX": px,
        "playerY": py,
        "playerZ": pz,
        "playerViewX": 200.0,
        "playerViewY": 0.0,
        "flashDuration": 2.5,
        "matchId": "an unknown key",
    }


# ---- frames mode ------------------------------------------------------------------------------


def test_frames_mode_counts_every_usable_enemy_pair(tmp_path: Path) -> None:
    """Round 1 (4 frames): 5 T (t2 unarmed, t1 without yaw in frame 1, t3 dead from frame 3)
    and 4 CT (ct1 unarmed, ct4 absent from frame 2). Ordered pairs with an armed attacker:
    frame 0: 4 T x 4 CT + 3 CT x 5 T = 31; frame 1: 3 x 4 + 3 x 4 = 24; frame 2: 4 x 3 + 2 x 5
    = 22; frame 3: 3 x 4 + 3 x 4 = 24; total 101. Round 2 (6 frames, all present): 31 per
    frame = 186, plus ct1's hit on t1 (unarmed in the frame, the gun from the event) = 187.
    Round 3 has no frames and only world damage: no samples."""
    samples, stats = build_samples([write(tmp_path, make_match())])
    groups, counts = np.unique(samples.group, return_counts=True)
    assert groups.tolist() == ["fixture-0001 r1", "fixture-0001 r2"]
    assert counts.tolist() == [101, 187]
    assert (stats.rounds_frames, stats.rounds_events, stats.rounds_without_samples) == (2, 1, 1)
    assert dict(stats.excluded) == {"world damage (no attacker)": 1}
    assert (stats.positives, stats.negatives) == (2, 286)
    assert set(samples.mode) == {"frames"}
    assert set(samples.attacker_weapon) == {"AK-47", "M4A4"}


def test_frames_mode_positives_by_hand(tmp_path: Path) -> None:
    """ct1 hits t1 for 27 at tick 5070 (nearest frame 1, tick 5064); ct2 hits t2 for 120 raw at
    tick 5100 (28 ticks before frame 2, 36 after frame 1): summed hpDamage capped at 100."""
    samples, _ = build_samples([write(tmp_path, make_match())])
    hits = samples.take(samples.hit)
    assert hits.tick.tolist() == [ROUND2_TICKS[1], ROUND2_TICKS[2]]
    assert hits.damage.tolist() == [27.0, 100.0]
    assert hits.hit_group.tolist() == [0, 0]  # Head
    assert hits.attacker_weapon.tolist() == ["M4A4", "M4A4"]
    np.testing.assert_allclose(hits.attacker_position[0], metres("ct1", 1))
    np.testing.assert_allclose(hits.victim_position[0], metres("t1", 1))
    np.testing.assert_allclose(hits.attacker_position[1], metres("ct2", 2))
    np.testing.assert_allclose(hits.victim_position[1], metres("t2", 2))
    assert hits.attacker_yaw.tolist() == [45.0 + 190.0, 90.0 + 190.0]  # viewX of CT players
    assert hits.victim_helmet.tolist() == [False, False]  # T players wear no helmet here
    negatives = samples.take(~samples.hit)
    assert (negatives.damage == 0).all() and (negatives.hit_group == -1).all()


def test_frames_mode_sums_hits_and_keeps_the_largest_hit_group(tmp_path: Path) -> None:
    document = make_match()
    extra = _damage(5060, "ct1", "t1", "M4A4", 40)  # also nearest frame 1
    extra["hitGroup"] = "LeftLeg"
    document["gameRounds"][1]["damages"].append(extra)
    samples, _ = build_samples([write(tmp_path, document)])
    hits = samples.take(samples.hit)
    assert hits.damage.tolist() == [67.0, 100.0]
    assert hits.hit_group.tolist() == [5, 0]  # Leg: the 40 HP hit is the larger


def test_frames_mode_moves_a_lethal_hit_to_the_frame_before(tmp_path: Path) -> None:
    """t1 dead from frame 2 of round 2: a hit at tick 5100 (nearest frame 2) lands in frame 1."""
    document = make_match()
    for frame in document["gameRounds"][1]["frames"][2:]:
        for player in frame["t"]["players"]:
            if player["name"] == "t1":
                player["hp"], player["isAlive"] = 0, False
    document["gameRounds"][1]["damages"] = [_damage(5100, "ct3", "t1", "M4A4", 100)]
    samples, stats = build_samples([write(tmp_path, document)])
    hits = samples.take(samples.hit)
    assert hits.tick.tolist() == [ROUND2_TICKS[1]]
    assert stats.realigned == 1


def test_frames_mode_drops_pairs_hit_only_by_excluded_damage(tmp_path: Path) -> None:
    document = make_match()
    grenade = _damage(5192, "ct3", "t3", "HE Grenade", 30)  # frame 3 of round 2
    grenade.update(weaponClass="Grenade", hitGroup="Generic")
    knife = _damage(5256, "ct3", "t3", "Knife", 40)  # frame 4
    document["gameRounds"][1]["damages"] += [grenade, knife]
    samples, stats = build_samples([write(tmp_path, document)])
    assert np.count_nonzero(samples.group == "fixture-0001 r2") == 187 - 2
    assert stats.excluded["grenade, fire or bomb"] == 1
    assert stats.excluded["weapon outside the vocabulary"] == 1


def test_friendly_fire_is_left_out(tmp_path: Path) -> None:
    document = make_match()
    friendly = _damage(5100, "ct2", "ct3", "M4A4", 20)
    friendly.update(victimSide="CT", isFriendlyFire=True)
    document["gameRounds"][1]["damages"].append(friendly)
    samples, stats = build_samples([write(tmp_path, document)])
    assert stats.excluded["friendly fire"] == 1
    assert int(samples.hit.sum()) == 2


# ---- events-only mode -------------------------------------------------------------------------


def test_events_mode_by_hand(tmp_path: Path) -> None:
    """Round 2 read from its events alone. Virtual frames every 64 ticks from the start tick
    4900. Positives: ct1 -> t1 (tick 5070) and ct2 -> t2 (5100), both in virtual frame 3
    (tick 5092). Anchors: frame 3 (the damages), frame 4 (the kill at 5130 and the plant at
    5182; tick 5156) and frame -2 (plant_begin at 4772, nobody seen within 2 s). Only the CT
    players have a known firearm. Frame 3: ct1 -> t2 and ct2 -> t1 (ct1 -> t1 and ct2 -> t2
    dealt damage); frame 4: t2 is dead, ct2 -> t1. Five samples."""
    samples, stats = build_samples([write(tmp_path, make_match())], mode="events")
    assert stats.rounds_events == 3 and stats.rounds_frames == 0
    assert len(samples) == 5 and set(samples.mode) == {"events"}
    hits = samples.take(samples.hit)
    assert hits.tick.tolist() == [5092, 5092]
    assert hits.damage.tolist() == [27.0, 100.0]
    np.testing.assert_allclose(hits.attacker_position[0], metres("ct1", 1))
    assert hits.attacker_yaw.tolist() == [90.0, 90.0]
    assert hits.victim_yaw.tolist() == [270.0, 270.0]
    assert hits.victim_hp.tolist() == [100, 100]
    assert hits.victim_helmet.tolist() == [True, True]  # head hits that removed armor
    negatives = samples.take(~samples.hit)
    pairs = sorted(
        (int(t), tuple(np.round(a, 3)), tuple(np.round(v, 3)))
        for t, a, v in zip(
            negatives.tick, negatives.attacker_position, negatives.victim_position, strict=True
        )
    )
    expected = sorted(
        [
            (5092, tuple(np.round(metres("ct1", 1), 3)), tuple(np.round(metres("t2", 1), 3))),
            (5092, tuple(np.round(metres("ct2", 1), 3)), tuple(np.round(metres("t1", 1), 3))),
            (5156, tuple(np.round(metres("ct2", 1), 3)), tuple(np.round(metres("t1", 1), 3))),
        ]
    )
    assert pairs == expected
    # t1 took 27 HP at tick 5070: 73 left at both anchors
    assert sorted(negatives.victim_hp.tolist()) == [73, 73, 100]
    assert set(negatives.attacker_weapon) == {"M4A4"}


def _t1_helmet(tmp_path: Path, armour_taken: int, round_num: int) -> bool:
    """The helmet events mode infers for t1 in round 2, whose two hits by ct1 (25 HP, then
    10 HP that took 4 armour) record no hit group, the first taking `armour_taken` armour."""
    document = make_match()
    document["gameRounds"] = document["gameRounds"][:2]  # round 2 last, whatever its number
    round2 = document["gameRounds"][1]
    round2["roundNum"] = round_num
    second = {**_damage(5080.0, "ct1", "t1", "M4A4", 10)}
    round2["damages"] = [_damage(5070.0, "ct1", "t1", "M4A4", 25), second, *round2["damages"][1:]]
    for row in round2["damages"][:2]:
        row["hitGroup"] = None
    round2["damages"][0]["armorDamage"] = round2["damages"][0]["armorDamageTaken"] = armour_taken
    tmp_path.mkdir()
    samples, _ = build_samples([write(tmp_path, document)], mode="events")
    hits = samples.take(samples.hit)
    (row,) = np.flatnonzero(hits.victim_position[:, 0] == metres("t1", 1)[0])
    assert hits.victim_armor[row] == 100  # the second hit took armour
    return bool(hits.victim_helmet[row])


def test_events_mode_infers_the_helmet_by_the_armour_rules(tmp_path: Path) -> None:
    """Without hit groups: 25 HP that took no armour from an armoured player is more than an
    M4A4 leg shot does at this range (23 HP at 776 u; 24 HP at 19.7 u, the distance in metres
    misread as Hammer units), so it was a bare head; hits that say nothing leave the helmet with
    the armour, except in a pistol round ($800 buys no helmet)."""
    assert _t1_helmet(tmp_path / "a", armour_taken=0, round_num=2) is False
    assert _t1_helmet(tmp_path / "b", armour_taken=4, round_num=2) is True
    assert _t1_helmet(tmp_path / "c", armour_taken=4, round_num=PISTOL_ROUND) is False


PISTOL_ROUND = 16 if TICK_RATE == 128 else 13  # CS:GO's MR15, CS2's MR12


@pytest.mark.parametrize(("round_num", "helmet"), [(2, True), (PISTOL_ROUND, False)])
def test_a_player_never_hit_wears_what_a_hit_one_would(
    tmp_path: Path, round_num: int, helmet: bool
) -> None:
    """t3, flashed but never hit, is a victim of negatives only: a helmet as the armoured hit
    players have, but none in a pistol round, where no hit player has one either (else the
    helmet would tell the samples apart)."""
    document = make_match()
    document["gameRounds"] = document["gameRounds"][:2]
    document["gameRounds"][1]["roundNum"] = round_num
    document["gameRounds"][1]["flashes"] = [flash(5100, "ct3", "t3")]
    samples, _ = build_samples([write(tmp_path, document)], mode="events")
    t3 = np.flatnonzero(np.all(np.isclose(samples.victim_position, metres("t3", 1)), axis=1))
    assert len(t3) == 4 and not samples.hit[t3].any()
    assert samples.victim_helmet[t3].tolist() == [helmet] * 4


def test_events_mode_uses_flashes(tmp_path: Path) -> None:
    """A flash by ct3 on t3 at tick 5100 places t3 (a new victim) near both anchors:
    frame 3 gains ct1 -> t3 and ct2 -> t3, frame 4 gains the same two."""
    document = make_match()
    document["gameRounds"][1]["flashes"] = [flash(5100, "ct3", "t3")]
    samples, _ = build_samples([write(tmp_path, document)], mode="events")
    assert len(samples) == 5 + 4
    assert int(samples.hit.sum()) == 2


def test_events_mode_window(tmp_path: Path) -> None:
    """With a 0.1 s window (12.8 ticks) no sighting is near an anchor: positives only."""
    samples, _ = build_samples([write(tmp_path, make_match())], mode="events", window_s=0.1)
    assert len(samples) == 2 and samples.hit.all()


def test_reader_reads_flashes(tmp_path: Path) -> None:
    document = make_match()
    document["gameRounds"][1]["flashes"] = [flash(5100, "ct3", "t3")]
    played = read_match(write(tmp_path, document)).round(2)
    row = played.flashes.iloc[0]
    assert row["attackerName"] == "ct3" and row["playerName"] == "t3"
    assert row["flashDuration"] == 2.5
    assert row["playerX_m"] == pytest.approx(expected_hammer_position("t3", 1)[0] * HAMMER_TO_M)
    assert row["frame_index"] == 2  # tick 5100 is nearest frame 2 (5128)
    assert len(read_match(write(tmp_path, make_match())).round(1).flashes) == 0


def _facing_views(document: dict[str, Any]) -> None:
    """Fill every damage and kill row's views as an export without them does: facing each
    other exactly."""
    for round_ in document["gameRounds"]:
        for row in round_["damages"] + round_["kills"]:
            if row.get("attackerX") is None:
                continue
            to_victim = float(
                np.degrees(
                    np.arctan2(row["victimY"] - row["attackerY"], row["victimX"] - row["attackerX"])
                )
            )
            row["attackerViewX"], row["victimViewX"] = to_victim, to_victim + 180.0


def test_views_filled_as_facing_are_redrawn_as_real_views_deviate(tmp_path: Path) -> None:
    """Views an export filled as facing each other teach that a hit victim looks at his
    attacker: they are redrawn from real hits' deviations, the same on every build, within
    the measured range, and counted; one recorded view (1 degree off) keeps them all."""
    document = make_match()
    _facing_views(document)
    faced = write(tmp_path, document, "faced.json.xz")
    first, stats = build_samples([faced], mode="events")
    again, _ = build_samples([faced], mode="events")
    np.testing.assert_array_equal(first.victim_yaw, again.victim_yaw)
    rows = sum(
        row.get("attackerX") is not None
        for r in document["gameRounds"]
        for row in r["damages"] + r["kills"]
    )
    assert stats.partial[FILLED_NOTE] == rows
    hits = first.take(first.hit)
    to_victim = np.degrees(
        np.arctan2(*(hits.victim_position - hits.attacker_position)[:, [1, 0]].T)
    )
    off = (hits.victim_yaw - to_victim) % 360.0 - 180.0  # the victim's view off his attacker
    assert np.all(off != 0.0) and np.all((off >= -161.5) & (off <= 170.1))
    attacker_off = (hits.attacker_yaw - to_victim + 180.0) % 360.0 - 180.0
    assert np.all(np.abs(attacker_off) <= 12.1)

    document["gameRounds"][1]["damages"][0]["victimViewX"] += 1.0
    recorded = write(tmp_path, document, "recorded.json.xz")
    kept, stats = build_samples([recorded], mode="events")
    assert FILLED_NOTE not in stats.partial
    assert sorted(kept.take(kept.hit).victim_yaw.tolist()) != sorted(hits.victim_yaw.tolist())


@pytest.mark.skipif(not EVENTS.is_dir(), reason="../shared/data/esta_dust2_events is absent")
def test_the_redrawn_views_deviate_as_the_real_hits_views_do() -> None:
    """The deviation tables are the quantiles of de_dust2's real firearm hits (396)."""
    rounds = read_match(next(EVENTS.glob("*.json.xz"))).rounds
    found = [hit_view_deviations(r) for r in rounds]
    attacker = np.concatenate([a for a, _ in found])
    victim = np.concatenate([v for _, v in found])
    assert len(attacker) == len(victim) == 396
    np.testing.assert_allclose(np.quantile(attacker, QUANTILES), ATTACKER_DEVIATION_DEG, atol=0.051)
    np.testing.assert_allclose(np.quantile(victim, QUANTILES), VICTIM_DEVIATION_DEG, atol=0.051)
    assert not any(filled_views(r) for r in rounds)  # recorded views stay as they are


@pytest.mark.skipif(not EVENTS.is_dir(), reason="../shared/data/esta_dust2_events is absent")
def test_real_events_file() -> None:
    """The real OG-NaVi match (events only): 503 damage rows, of which 107 are left out."""
    samples, stats = build_samples([EVENTS])
    assert stats.rounds_events == 18 and stats.rounds_frames == 0
    assert sum(stats.excluded.values()) == 107
    hits = samples.take(samples.hit)
    assert 200 < len(hits) < 396  # 396 usable rows, grouped per pair and step
    assert ((hits.damage >= 1) & (hits.damage <= 100)).all()
    assert (~samples.hit).sum() > len(hits)
    assert np.isfinite(samples.features(FeatureSpec()).coords).all()


# ---- bad input --------------------------------------------------------------------------------


def test_no_usable_samples_is_one_error(tmp_path: Path) -> None:
    document = make_match()
    document["gameRounds"] = [document["gameRounds"][2]]  # events only, world damage only
    with pytest.raises(DecoyError, match="no usable samples"):
        build_samples([write(tmp_path, document)])


def test_forced_frames_mode_skips_rounds_without_frames(tmp_path: Path) -> None:
    _, stats = build_samples([write(tmp_path, make_match())], mode="frames")
    assert stats.rounds_frames == 2 and stats.rounds_events == 0
    assert stats.rounds_without_samples == 1


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [({"mode": "movie"}, "mode must be"), ({"window_s": 0.0}, "positive number")],
)
def test_bad_options(tmp_path: Path, kwargs: dict[str, Any], message: str) -> None:
    with pytest.raises(DecoyError, match=message):
        build_samples([write(tmp_path, make_match())], **kwargs)


def test_missing_data_path(tmp_path: Path) -> None:
    with pytest.raises(DecoyError, match="no such file"):
        build_samples([tmp_path / "nothing.json.xz"])


def test_a_corrupt_file_is_a_recorded_failure(tmp_path: Path) -> None:
    """The one round loop: an unreadable file is a failure in the stats, the others are used."""
    good = write(tmp_path, make_match())
    (tmp_path / "corrupt.json.xz").write_bytes(b"not an xz stream")
    samples, stats = build_samples([tmp_path])
    assert len(samples) == 288 and stats.files == 2
    assert [(Path(f.file).name, f.round_num, f.kind) for f in stats.failures] == [
        ("corrupt.json.xz", None, "unreadable file")
    ]
    assert (stats.file_errors, stats.round_errors) == (1, 0)
    assert stats.to_json()["failures"][0]["kind"] == "unreadable file"
    assert good.exists()


def test_a_round_whose_samples_fail_is_recorded(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """A round whose sample building raises is one failure (a bug: "internal error", named
    with where it was raised), its counts are left out, and the other rounds are used."""
    import decoy_cli.modeling.samples as module

    real = module.frame_samples

    def flaky(round_: Round, stats: SampleStats) -> Samples:
        if round_.round_num == 1:
            stats.realigned += 99
            raise ValueError("boom")
        return real(round_, stats)

    monkeypatch.setattr(module, "frame_samples", flaky)
    samples, stats = build_samples([write(tmp_path, make_match())])
    assert np.unique(samples.group).tolist() == ["fixture-0001 r2"]
    [failure] = stats.failures
    assert (failure.round_num, failure.kind) == (1, "internal error")
    assert failure.message.startswith("ValueError: boom (at ")
    assert stats.round_errors == 1 and stats.rounds_frames == 1 and stats.realigned < 99


def test_only_failed_inputs_is_one_error(tmp_path: Path) -> None:
    (tmp_path / "corrupt.json.xz").write_bytes(b"not an xz stream")
    with pytest.raises(DecoyError, match=r"no usable samples .*1 input failed: "):
        build_samples([tmp_path])


# ---- features, split and balance --------------------------------------------------------------


def synthetic(groups: int, per_group: int, matches: int = 1, seed: int = 0) -> Samples:
    """Samples with random states, a few positives per group, `matches` matches."""
    rng = np.random.default_rng(seed)
    k = groups * per_group
    group = np.repeat([f"m{g % matches} r{g}" for g in range(groups)], per_group).astype(object)
    hit = rng.random(k) < 0.3
    return Samples(
        map_name=np.full(k, "de_dust2", dtype=object),
        attacker_position=rng.uniform(-40, 40, (k, 3)),
        victim_position=rng.uniform(-40, 40, (k, 3)),
        attacker_yaw=rng.uniform(0, 360, k),
        victim_yaw=rng.uniform(0, 360, k),
        attacker_hp=np.full(k, 100, np.int16),
        victim_hp=np.full(k, 100, np.int16),
        attacker_weapon=np.full(k, "AK-47", dtype=object),
        victim_armor=np.full(k, 100, np.int16),
        victim_helmet=np.ones(k, bool),
        hit=hit,
        damage=np.where(hit, 27.0, 0.0).astype(np.float32),
        hp_lost=np.where(hit, 27.0, 0.0).astype(np.float32),
        hit_group=np.where(hit, 2, -1).astype(np.int8),
        group=group,
        match=np.array([g.split()[0] for g in group], dtype=object),
        tick=np.arange(k, dtype=np.int64),
        mode=np.full(k, "frames", dtype=object),
    )


def test_features_keep_sample_order_across_maps() -> None:
    samples = synthetic(4, 5)
    maps = np.array(["de_dust2", "de_inferno"] * 10, dtype=object)
    mixed = dataclasses.replace(samples, map_name=maps)
    features = mixed.features(FeatureSpec())
    assert features.map.argmax(1).tolist() == [map_index(m) for m in maps]
    single = samples.features(FeatureSpec())
    np.testing.assert_array_equal(features.coords, single.coords)


@pytest.mark.parametrize("by", ["round", "match"])
def test_split_never_shares_a_unit(by: str) -> None:
    samples = synthetic(groups=20, per_group=7, matches=10)
    split = split_samples(samples, by, seed=3, val_fraction=0.2, test_fraction=0.2)
    unit = samples.group if by == "round" else samples.match
    parts = [set(unit[split.part(name)]) for name in ("train", "val", "test")]
    assert not (parts[0] & parts[1] or parts[0] & parts[2] or parts[1] & parts[2])
    assert np.array_equal(split.part("all"), np.arange(len(samples)))
    counts = [len(p) for p in parts]
    assert counts == ([12, 4, 4] if by == "round" else [6, 2, 2])


def test_split_is_seeded() -> None:
    samples = synthetic(groups=20, per_group=3)
    one = split_samples(samples, "round", 1, 0.15, 0.15)
    again = split_samples(samples, "round", 1, 0.15, 0.15)
    other = split_samples(samples, "round", 2, 0.15, 0.15)
    assert one.units == again.units
    assert one.units != other.units


def test_split_by_match_needs_three_matches() -> None:
    with pytest.raises(DecoyError, match="use --split round"):
        split_samples(synthetic(groups=10, per_group=3), "match", 0, 0.15, 0.15)


@pytest.mark.parametrize(
    ("by", "val", "test"), [("sample", 0.1, 0.1), ("round", 0.0, 0.1), ("round", 0.5, 0.5)]
)
def test_split_bad_options(by: str, val: float, test: float) -> None:
    with pytest.raises(DecoyError):
        split_samples(synthetic(groups=10, per_group=3), by, 0, val, test)


def test_balance_keeps_every_positive_and_as_many_negatives() -> None:
    samples = synthetic(groups=10, per_group=20)
    index = np.arange(0, len(samples), 2)
    chosen = balance(samples, index, seed=5)
    assert set(chosen) <= set(index)
    assert set(index[samples.hit[index]]) <= set(chosen)
    assert samples.hit[chosen].sum() * 2 == len(chosen)
    np.testing.assert_array_equal(chosen, balance(samples, index, seed=5))


def test_take_and_concat_round_trip() -> None:
    samples = synthetic(groups=3, per_group=4)
    both = Samples.concat([samples.take(slice(0, 5)), samples.take(slice(5, None))])
    for name in samples.__dataclass_fields__:
        np.testing.assert_array_equal(getattr(both, name), getattr(samples, name))
    assert len(Samples.concat([])) == 0
