"""The ESTA writer: hand-built rounds written as awpy 1.x JSON read back by `read_match` to the
same positions (within float32), HP, flags, events and outcome; the key sets of real files;
deterministic bytes; and the inputs it refuses."""

from __future__ import annotations

import dataclasses
import json
import lzma
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd
import pytest
from esta_fixtures import make_match

from decoy_cli.csgo import HAMMER_TO_M
from decoy_cli.errors import OutputError
from decoy_cli.esta import read_match
from decoy_cli.esta.records import (
    BombEventRecord,
    DamageRecord,
    EstaRoundRecord,
    KillRecord,
    MatchRecord,
    PlayerRecord,
)
from decoy_cli.esta.writer import encode_match, match_document, write_match

DATA = Path(__file__).resolve().parents[1].parent / "shared" / "data"
TSIDE = DATA / "esta_dust2_tside"
EVENTS = DATA / "esta_dust2_events"

PLAYERS = [
    PlayerRecord("alpha", 76561198000000001, "T", ("AK-47", "Glock-18", "Knife"), 4700, 200, 4500),
    PlayerRecord("beta", None, "T", ("Glock-18", "Knife"), 200, 200, 0),
    PlayerRecord("gamma", 76561198000000003, "CT", ("M4A4", "USP-S", "Knife"), 5500, 200, 5300),
    PlayerRecord("delta", 76561198000000004, "CT", ("USP-S", "Knife"), 850, 200, 650),
]
KEYS = ["76561198000000001", "beta", "76561198000000003", "76561198000000004"]
"""The reader's keys: steamID as a string, else the name (beta has no steamID)."""

FREEZE_END = 990
TICKS = np.array([1000, 1064, 1128, 1192], dtype=np.int64)
PLANT_TICK = 1100
TICK_RATE = 128

REAL_TSIDE_PLAYER_KEYS = {
    "steamID", "name", "team", "side", "x", "y", "z", "velocityX", "velocityY", "velocityZ",
    "viewX", "viewY", "hp", "armor", "totalUtility", "isAlive", "isDefusing", "isPlanting",
    "isReloading", "isInBombZone", "isInBuyZone", "equipmentValue",
    "equipmentValueFreezetimeEnd", "equipmentValueRoundStart", "cash", "cashSpendThisRound",
    "cashSpendTotal", "hasHelmet", "hasDefuse", "hasBomb", "activeWeapon",
}  # fmt: skip
"""The player keys of the real T-side files (../shared/data/esta_dust2_tside)."""


def _positions() -> np.ndarray:
    """(4, 4, 3) metres with awkward decimals; delta is absent from frame 2."""
    i, j = np.meshgrid(np.arange(4), np.arange(4), indexing="ij")
    position = np.stack(
        [-10.0 + 3.1 * i + 0.3717 * j, 5.5 - 1.13 * i + 0.2911 * j, 0.123 * i - 0.05 * j], axis=2
    )
    position[3, 2] = np.nan
    return position


def make_round(num: int = 1) -> EstaRoundRecord:
    """Round 1: alpha plants at A, gamma kills beta at frame 2, delta is absent from frame 2."""
    alive = np.ones((4, 4), dtype=bool)
    alive[1, 2:] = False
    hp = np.full((4, 4), 100, dtype=np.int16)
    hp[1, 1] = 45
    hp[1, 2:] = 0
    hp[0, 1:] = 95
    weapon = np.array(
        [["AK-47"] * 4, ["Glock-18", "Glock-18", "", ""], ["M4A4"] * 4, ["USP-S"] * 4]
    )
    position = _positions()
    bomb = np.vstack([position[0, :2], np.repeat(position[0, 2][None], 2, axis=0)])
    has_bomb = np.zeros((4, 4), dtype=bool)
    has_bomb[0, :2] = True
    planted = np.array([False, False, True, True])
    planting = np.zeros((4, 4), dtype=bool)
    planting[0, 1] = True
    return EstaRoundRecord(
        round_num=num,
        start_tick=900,
        freeze_end_tick=FREEZE_END,
        end_tick=1192,
        end_official_tick=1192 + 896,
        frame_ticks=TICKS,
        players=PLAYERS,
        position=position,
        yaw=np.array([[10.5, 20.25, -170.0, 359.9]] * 4) + np.arange(4)[:, None],
        hp=hp,
        armor=np.array([[100] * 4, [0] * 4, [100] * 4, [0] * 4]),
        helmet=np.array([[True] * 4, [False] * 4, [True] * 4, [False] * 4]),
        has_defuser=np.array([[False] * 4, [False] * 4, [True] * 4, [False] * 4]),
        weapon=weapon,
        alive=alive,
        has_bomb=has_bomb,
        bomb_position=bomb,
        bomb_planted=planted,
        bombsite=np.where(planted, "A", ""),
        winning_side="T",
        end_reason="TargetBombed",
        bomb_plant_tick=PLANT_TICK,
        damages=[
            DamageRecord(
                1060, 2, 1, "M4A4", 55, 55, "Chest", position[2, 1], position[1, 1], 200.0, 20.0
            ),
            DamageRecord(
                1125, 2, 1, "M4A4", 110, 45, "Head", position[2, 2], position[1, 1], 201.0, 21.0
            ),
            DamageRecord(1070, -1, 0, "World", 5, 5, "Generic", None, position[0, 1], None, 30.0),
        ],
        kills=[
            KillRecord(
                1125,
                2,
                1,
                "M4A4",
                position[2, 2],
                position[1, 1],
                201.0,
                21.0,
                is_headshot=True,
                is_first_kill=True,
            )
        ],
        bomb_events=[
            BombEventRecord(PLANT_TICK - 410, 0, "plant_begin", "A", position[0, 1]),
            BombEventRecord(PLANT_TICK, 0, "plant", "A", position[0, 2]),
        ],
        planting=planting,
        place=np.full((4, 4), "LongA"),
    )


def quiet_round(num: int = 2) -> EstaRoundRecord:
    """A round without events or bomb that the CT win."""
    base = make_round(num)
    return dataclasses.replace(
        base,
        start_tick=3000,
        freeze_end_tick=3100,
        end_tick=3292,
        end_official_tick=4000,
        frame_ticks=TICKS + 2100,
        bomb_position=np.full((4, 3), np.nan),
        bomb_planted=np.zeros(4, dtype=bool),
        bombsite=np.full(4, ""),
        has_bomb=np.zeros((4, 4), dtype=bool),
        winning_side="CT",
        end_reason="CTWin",
        bomb_plant_tick=None,
        damages=[],
        kills=[],
        bomb_events=[],
        planting=None,
        place=None,
    )


def make_record(rounds: list[EstaRoundRecord] | None = None) -> MatchRecord:
    return MatchRecord(
        match_id="writer-test",
        map_name="de_dust2",
        tick_rate=TICK_RATE,
        rounds=[make_round(1), quiet_round(2)] if rounds is None else rounds,
        team_names={"T": "Team T", "CT": "Team CT"},
        provenance={"synthetic": True, "note": "hand-built in tests/test_esta_writer.py"},
        client_name="tests",
    )


@pytest.fixture(scope="module")
def written(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return write_match(make_record(), tmp_path_factory.mktemp("writer") / "m.json.xz")


def _raw(path: Path) -> dict[str, Any]:
    return json.loads(lzma.decompress(path.read_bytes()))


def test_round_trip_frames(written: Path) -> None:
    match = read_match(written)
    assert (match.match_id, match.map_name, match.tick_rate) == ("writer-test", "de_dust2", 128)
    assert match.round_errors == {} and [r.round_num for r in match.rounds] == [1, 2]
    assert match.meta["provenance"]["synthetic"] is True
    assert match.meta["clientName"] == "tests"
    original = make_round()
    r = match.round(1)
    assert [p.key for p in r.players] == KEYS
    assert [p.side for p in r.players] == ["T", "T", "CT", "CT"]
    np.testing.assert_array_equal(r.frame_ticks, TICKS)
    np.testing.assert_allclose(r.frame_seconds, (TICKS - FREEZE_END) / TICK_RATE)
    present = np.isfinite(original.position).all(axis=2)
    np.testing.assert_array_equal(r.present, present)
    # float32 Hammer units: relative precision 6e-8, far inside 1e-6
    np.testing.assert_allclose(r.position[present], original.position[present], rtol=1e-6)
    assert np.isnan(r.position[3, 2]).all()
    np.testing.assert_allclose(r.yaw[present], original.yaw[present], rtol=1e-6)
    np.testing.assert_array_equal(r.hp[present], original.hp[present])
    assert r.hp[3, 2] == -1  # absent
    for name in ("armor", "helmet", "has_defuser", "alive", "has_bomb", "weapon"):
        np.testing.assert_array_equal(getattr(r, name)[present], getattr(original, name)[present])
    np.testing.assert_allclose(r.bomb_position, original.bomb_position, rtol=1e-6)
    np.testing.assert_array_equal(r.bomb_planted, original.bomb_planted)
    np.testing.assert_array_equal(r.bombsite, ["", "", "A", "A"])
    assert (r.winning_side, r.end_reason, r.bomb_plant_tick) == ("T", "TargetBombed", PLANT_TICK)
    assert (r.start_tick, r.end_tick) == (900, 1192)
    quiet = match.round(2)
    assert (quiet.winning_side, quiet.end_reason, quiet.bomb_plant_tick) == ("CT", "CTWin", None)
    assert np.isnan(quiet.bomb_position).all()


def test_round_trip_events(written: Path) -> None:
    r = read_match(written).round(1)
    original = make_round()
    damages = r.damages
    assert list(damages["attackerName"].fillna("")) == ["gamma", "gamma", ""]
    assert list(damages["victimName"]) == ["beta", "beta", "alpha"]
    assert list(damages["hpDamage"]) == [55, 110, 5]
    assert list(damages["hpDamageTaken"]) == [55, 45, 5]
    assert list(damages["hitGroup"]) == ["Chest", "Head", "Generic"]
    assert list(damages["weaponClass"].fillna("")) == ["Rifle", "Rifle", ""]
    assert list(damages["frame_index"]) == [1, 2, 1]
    assert damages["attackerSide"].iloc[0] == "CT" and damages["victimSide"].iloc[0] == "T"
    np.testing.assert_allclose(
        damages[["victimX_m", "victimY_m", "victimZ_m"]].to_numpy()[0],
        original.position[1, 1],
        rtol=1e-6,
    )
    expected = np.linalg.norm(original.position[2, 1] - original.position[1, 1]) / HAMMER_TO_M
    assert damages["distance"].iloc[0] == pytest.approx(expected, rel=1e-6)
    assert np.isnan(damages["attackerX"].iloc[2])
    assert damages["victimSteamID"].iloc[0] is pd.NA  # beta has no steamID
    kill = r.kills.iloc[0]
    assert (kill["attackerName"], kill["victimName"], kill["weapon"]) == ("gamma", "beta", "M4A4")
    assert bool(kill["isHeadshot"]) and bool(kill["isFirstKill"]) and not bool(kill["isTrade"])
    assert list(r.bomb_events["bombAction"]) == ["plant_begin", "plant"]
    assert list(r.bomb_events["bombSite"]) == ["A", "A"]
    assert list(r.bomb_events["playerName"]) == ["alpha", "alpha"]


def test_document_scores_clock_and_flags(written: Path) -> None:
    raw = _raw(written)
    first, second = raw["gameRounds"]
    assert (first["tScore"], first["ctScore"], first["endTScore"], first["endCTScore"]) == (
        0,
        0,
        1,
        0,
    )
    assert (second["tScore"], second["endCTScore"]) == (1, 1)
    assert (first["winningTeam"], first["losingTeam"]) == ("Team T", "Team CT")
    assert first["tFreezeTimeEndEqVal"] == 4900 and first["tBuyType"] == "Full Eco"
    assert first["ctRoundSpendMoney"] == 5950 and first["ctBuyType"] == "Semi Eco"
    frames = first["frames"]
    # the round clock before the plant (115 s - 0.08 s), the bomb timer after it
    assert frames[0]["clockTime"] == "01:55"
    assert frames[2]["clockTime"] == "00:40"
    alpha = next(p for p in frames[1]["t"]["players"] if p["name"] == "alpha")
    assert alpha["isPlanting"] and alpha["hasBomb"]
    assert [i["weaponName"] for i in alpha["inventory"]] == ["AK-47", "Glock-18", "Knife", "C4"]
    assert alpha["eyeZ"] == pytest.approx(alpha["z"] + 64, abs=1e-3)
    dt = (TICKS[1] - TICKS[0]) / TICK_RATE
    expected_vx = (make_round().position[0, 1, 0] - make_round().position[0, 0, 0]) / dt
    assert alpha["velocityX"] == pytest.approx(expected_vx / HAMMER_TO_M, rel=1e-5)
    assert alpha["lastPlaceName"] == "LongA"
    assert frames[2]["t"]["alivePlayers"] == 1 and len(frames[2]["ct"]["players"]) == 1
    assert raw["playbackTicks"] == 4000
    assert raw["provenance"]["synthetic"] is True
    assert [f["globalFrameID"] for f in second["frames"]] == [4, 5, 6, 7]


def test_key_sets_of_the_real_format(written: Path) -> None:
    """Every key of the fixture's awpy 1.x player, frame and round, and of the real T-side
    player, is written."""
    raw = _raw(written)
    fixture = make_match()
    f_round = fixture["gameRounds"][1]
    f_frame = f_round["frames"][0]
    unknown = {"someNewKey"}
    round_ = raw["gameRounds"][0]
    frame = round_["frames"][0]
    player = frame["t"]["players"][0]
    assert set(f_frame["t"]["players"][0]) - unknown <= set(player)
    assert set(player) >= REAL_TSIDE_PLAYER_KEYS
    assert set(f_frame) - unknown <= set(frame)
    assert set(f_frame["t"]) - unknown <= set(frame["t"])
    assert set(f_round) - unknown <= set(round_)
    assert set(fixture) - unknown <= set(raw)
    assert set(f_round["damages"][0]) - unknown <= set(round_["damages"][0])
    assert set(f_round["bombEvents"][0]) <= set(round_["bombEvents"][0])


@pytest.mark.skipif(not TSIDE.is_dir() or not EVENTS.is_dir(), reason="../shared/data is absent")
def test_key_sets_of_real_files(written: Path) -> None:
    """The keys of real player states, rounds and events are all written."""
    raw = _raw(written)
    ours = raw["gameRounds"][0]
    real_tside = json.loads(lzma.decompress(sorted(TSIDE.glob("*.json.xz"))[0].read_bytes()))
    real_round = real_tside["gameRounds"][0]
    assert set(real_round["frames"][0]["t"]["players"][0]) <= set(
        ours["frames"][0]["t"]["players"][0]
    )
    assert set(real_round["frames"][0]) <= set(ours["frames"][0])
    events = json.loads(lzma.decompress(sorted(EVENTS.glob("*.json.xz"))[0].read_bytes()))
    real = next(r for r in events["gameRounds"] if r["kills"] and r["bombEvents"])
    assert set(real) <= set(ours)
    assert set(real["damages"][0]) <= set(ours["damages"][0])
    assert set(real["kills"][0]) <= set(ours["kills"][0])
    assert set(real["bombEvents"][0]) <= set(ours["bombEvents"][0])


def test_plain_json_and_determinism(tmp_path: Path) -> None:
    plain = write_match(make_record(), tmp_path / "m.json")
    assert json.loads(plain.read_bytes())["matchID"] == "writer-test"
    assert read_match(plain).round(1).end_reason == "TargetBombed"
    one = write_match(make_record(), tmp_path / "a.json.xz").read_bytes()
    two = write_match(make_record(), tmp_path / "b.json.xz").read_bytes()
    assert one == two
    assert encode_match(make_record()) == encode_match(make_record())


def test_bad_output_paths(tmp_path: Path) -> None:
    with pytest.raises(OutputError, match=r"ends in \.json\.xz or \.json"):
        write_match(make_record(), tmp_path / "m.txt")
    (tmp_path / "d.json.xz").mkdir()
    with pytest.raises(OutputError, match="it is a directory"):
        write_match(make_record(), tmp_path / "d.json.xz")
    blocker = tmp_path / "file"
    blocker.write_text("")
    with pytest.raises(OutputError, match="cannot write"):
        write_match(make_record(), blocker / "m.json.xz")


@pytest.mark.parametrize(
    ("change", "message"),
    [
        ({"weapon": np.full((4, 4), "Banana")}, "unknown weapon 'Banana'"),
        ({"hp": np.zeros((4, 3))}, r"hp has shape \(4, 3\), expected \(4, 4\)"),
        ({"end_reason": "Surrender"}, "unknown round end reason 'Surrender'"),
        ({"winning_side": "X"}, "winning side 'X' is not T or CT"),
        ({"frame_ticks": TICKS[::-1].copy()}, "frame ticks go backwards"),
        (
            {"bomb_events": [BombEventRecord(1, 0, "boom", "A", (0.0, 0.0, 0.0))]},
            "unknown bomb action 'boom'",
        ),
        (
            {"damages": [DamageRecord(1, 2, 9, "M4A4", 1, 1, "Head", None, (0, 0, 0), None, 0)]},
            "no player 9",
        ),
        (
            {"damages": [DamageRecord(1, 2, 1, "M4A4", 1, 1, "Arm", None, (0, 0, 0), None, 0)]},
            "unknown hit group 'Arm'",
        ),
    ],
)
def test_refused_inputs(change: dict[str, Any], message: str) -> None:
    bad = dataclasses.replace(make_round(), **change)
    with pytest.raises(ValueError, match=message):
        match_document(make_record([bad]))


def test_duplicate_players_and_rounds_are_refused() -> None:
    twin = dataclasses.replace(make_round(), players=[PLAYERS[0], PLAYERS[0], *PLAYERS[2:]])
    with pytest.raises(ValueError, match="share a steamID or name"):
        match_document(make_record([twin]))
    with pytest.raises(ValueError, match="round numbers must be unique"):
        match_document(make_record([make_round(1), make_round(1)]))
