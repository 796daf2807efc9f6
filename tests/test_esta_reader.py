"""The ESTA reader on generated fixtures (tests/esta_fixtures.py) and on the real shared data."""

from __future__ import annotations

import lzma
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from esta_fixtures import (
    BOMB_HAMMER,
    CT_KEYS,
    DEAD_T,
    MATCH_ID,
    MISSING_CT,
    ROUND1_FREEZE_END,
    ROUND1_TICKS,
    ROUND2_FREEZE_END,
    ROUND2_PLANT_TICK,
    ROUND2_TICKS,
    T_KEYS,
    TICK_RATE,
    encode,
    expected_hammer_position,
    make_match,
    write_match,
)
from typer.testing import CliRunner

from decoy_cli.cli import app
from decoy_cli.csgo import HAMMER_TO_M
from decoy_cli.errors import EstaError
from decoy_cli.esta import (
    MISSING,
    Match,
    Round,
    iter_match_files,
    load_round,
    parse_round_address,
    read_match,
)
from decoy_cli.esta.schema import BOMB_EVENT_COLUMNS, DAMAGE_COLUMNS, KILL_COLUMNS

DATA = Path(__file__).resolve().parents[1].parent / "shared" / "data"
TSIDE = DATA / "esta_dust2_tside"
EVENTS = DATA / "esta_dust2_events" / "og-navi-blast2020-r01-18.json.xz"

runner = CliRunner()


@pytest.fixture(scope="module")
def match_file(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return write_match(tmp_path_factory.mktemp("esta") / "fixture.json.xz")


@pytest.fixture(scope="module")
def match(match_file: Path) -> Match:
    return read_match(match_file)


def _row(played: Round, key: str) -> int:
    return [p.key for p in played.players].index(key)


def _write(tmp_path: Path, document: Any, name: str = "bad.json") -> Path:
    return write_match(tmp_path / name, document)


def _round_error(tmp_path: Path, document: dict[str, Any], num: int) -> str:
    """Read a match whose round `num` is bad: the others read fine, that one raises."""
    path = _write(tmp_path, document)
    result = read_match(path)
    assert num in result.round_errors
    assert [r.round_num for r in result.rounds] == sorted({1, 2, 3} - {num})
    with pytest.raises(EstaError) as caught:
        result.round(num)
    message = str(caught.value)
    assert message.startswith(f"{path}: round {num}: ")
    assert "\n" not in message
    return message


def _file_error(path: Path) -> str:
    with pytest.raises(EstaError) as caught:
        read_match(path)
    message = str(caught.value)
    assert str(path) in message
    assert "\n" not in message
    return message


# --- the fixture match --------------------------------------------------------------------


def test_match_metadata(match: Match, match_file: Path) -> None:
    assert match.match_id == MATCH_ID
    assert match.path == match_file
    assert match.map_name == "de_dust2"
    assert match.tick_rate == TICK_RATE
    assert match.meta["provenance"]["note"].startswith("generated")
    assert match.meta["serverVars"]["bombTimer"] == 40
    assert not {"gameRounds", "matchID", "mapName", "tickRate"} & set(match.meta)
    assert [r.round_num for r in match.rounds] == [1, 2, 3]
    assert match.round_errors == {}
    assert match.round_numbers == [1, 2, 3]


def test_plain_json_reads_like_xz(match: Match, tmp_path: Path) -> None:
    plain = read_match(write_match(tmp_path / "fixture.json"))
    assert plain.match_id == match.match_id
    for a, b in zip(plain.rounds, match.rounds, strict=True):
        np.testing.assert_array_equal(a.position, b.position)
        np.testing.assert_array_equal(a.weapon, b.weapon)


def test_xz_is_recognised_by_content_not_name(tmp_path: Path) -> None:
    path = write_match(tmp_path / "compressed.json", compress=True)
    assert read_match(path).match_id == MATCH_ID


def test_players_keyed_by_steamid_else_name(match: Match) -> None:
    played = match.round(1)
    assert [p.key for p in played.players] == T_KEYS + CT_KEYS
    by_key = {p.key: p for p in played.players}
    assert by_key["t4"].steam_id is None and by_key["t4"].name == "t4"
    assert by_key["BOT t5"].steam_id is None  # bots have steamID 0
    assert by_key[CT_KEYS[0]].steam_id == int(CT_KEYS[0])
    assert by_key[CT_KEYS[0]].name == "ct1"
    assert [p.side for p in played.players] == ["T"] * 5 + ["CT"] * 4
    np.testing.assert_array_equal(played.side_indices("T"), np.arange(5))
    np.testing.assert_array_equal(played.side_indices("CT"), np.arange(5, 9))
    assert played.num_players == 9
    assert played.num_frames == len(ROUND1_TICKS)


def test_positions_in_metres_whatever_the_order_in_frames(match: Match) -> None:
    played = match.round(1)
    for player in played.players:
        row = _row(played, player.key)
        for j in range(played.num_frames):
            if played.present[row, j]:
                expected = np.array(expected_hammer_position(player.name, j)) * HAMMER_TO_M
                np.testing.assert_allclose(played.position[row, j], expected)
    assert played.position.shape == (9, 4, 3)
    assert played.position.dtype == np.float64


def test_player_missing_from_a_frame_is_absent(match: Match) -> None:
    name, num, frame = MISSING_CT
    played = match.round(num)
    row = [p.name for p in played.players].index(name)
    assert not played.present[row, frame]
    assert not played.alive[row, frame]
    assert np.isnan(played.position[row, frame]).all()
    assert np.isnan(played.yaw[row, frame])
    assert played.hp[row, frame] == MISSING and played.armor[row, frame] == MISSING
    assert played.weapon[row, frame] == ""
    assert played.present.sum() == 9 * 4 - 1


def test_values_types_and_nulls(match: Match) -> None:
    played = match.round(1)
    assert played.hp.dtype == np.int16 and played.armor.dtype == np.int16
    for name in ("helmet", "has_defuser", "alive", "present", "has_bomb"):
        assert getattr(played, name).dtype == bool
    assert played.weapon.dtype.kind == "U"
    t1, t2 = _row(played, T_KEYS[0]), _row(played, T_KEYS[1])
    ct1 = _row(played, CT_KEYS[0])
    assert played.hp[t1, 0] == 100  # written as 100.0
    assert np.isnan(played.yaw[t1, 1]) and played.yaw[t1, 2] == 100.0  # viewX null in frame 1
    assert played.weapon[t1, 0] == "AK-47"
    assert played.weapon[t2, 0] == ""  # "" in the file
    assert played.weapon[ct1, 0] == ""  # null in the file
    assert played.has_bomb[t1].all() and not played.has_bomb[t2].any()
    assert (
        played.has_defuser[ct1].all() and played.helmet[ct1].all() and not played.helmet[t1].any()
    )


def test_alive_from_is_alive_else_hp(match: Match) -> None:
    name, num, frame = DEAD_T
    played = match.round(num)
    row = [p.name for p in played.players].index(name)
    assert played.alive[row, :frame].all() and not played.alive[row, frame:].any()
    assert played.hp[row, frame] == 0
    t2 = _row(match.round(2), T_KEYS[1])
    assert match.round(2).alive[t2].all()  # isAlive null, hp 100


def test_seconds_given_or_derived_from_ticks(match: Match) -> None:
    first, second = match.round(1), match.round(2)
    np.testing.assert_array_equal(first.frame_ticks, ROUND1_TICKS)
    assert first.frame_ticks.dtype == np.int64
    expected = (np.array(ROUND1_TICKS) - ROUND1_FREEZE_END) / TICK_RATE
    np.testing.assert_allclose(first.frame_seconds, expected)
    # frame 1 of round 2 has seconds null: derived from freezeTimeEndTick
    expected = (np.array(ROUND2_TICKS) - ROUND2_FREEZE_END) / TICK_RATE
    np.testing.assert_allclose(second.frame_seconds, expected)


def test_seconds_without_freeze_end_use_the_other_frames(tmp_path: Path) -> None:
    document = make_match()
    first = document["gameRounds"][0]
    first["freezeTimeEndTick"] = None
    first["frames"][2]["seconds"] = None
    played = read_match(_write(tmp_path, document)).round(1)
    expected = (np.array(ROUND1_TICKS) - ROUND1_FREEZE_END) / TICK_RATE
    np.testing.assert_allclose(played.frame_seconds, expected)


def test_seconds_all_null_count_from_start_tick(tmp_path: Path) -> None:
    document = make_match()
    first = document["gameRounds"][0]
    first["freezeTimeEndTick"] = None
    for frame in first["frames"]:
        frame["seconds"] = None
    played = read_match(_write(tmp_path, document)).round(1)
    np.testing.assert_allclose(played.frame_seconds, (np.array(ROUND1_TICKS) - 900) / TICK_RATE)


def test_bomb_and_round_facts(match: Match) -> None:
    played = match.round(2)
    assert played.bomb_plant_tick == ROUND2_PLANT_TICK
    np.testing.assert_array_equal(played.bomb_planted, [False, False, False, True, True, True])
    assert list(played.bombsite) == ["", "", "", "A", "A", "A"]
    assert np.isnan(played.bomb_position[0]).all()  # bomb null in frame 0
    np.testing.assert_allclose(played.bomb_position[3], np.array(BOMB_HAMMER) * HAMMER_TO_M)
    assert played.winning_side == "T" and played.end_reason == "TargetBombed"
    assert (played.start_tick, played.end_tick) == (4900, 5400)
    assert match.round(1).bomb_plant_tick is None


def test_event_tables(match: Match) -> None:
    played = match.round(2)
    damages, kills, bombs = played.damages, played.kills, played.bomb_events
    assert list(damages.columns[: len(DAMAGE_COLUMNS)]) == list(DAMAGE_COLUMNS)
    assert list(kills.columns[: len(KILL_COLUMNS)]) == list(KILL_COLUMNS)
    assert list(bombs.columns[: len(BOMB_EVENT_COLUMNS)]) == list(BOMB_EVENT_COLUMNS)
    assert "someNewKey" not in damages.columns
    assert list(damages["tick"]) == [5070, 5100]  # 5070.0 in the file
    assert str(damages["tick"].dtype) == "Int64"
    assert list(damages["hpDamage"]) == [27, 120]
    assert list(damages["frame_index"]) == [1, 2]  # nearest frame tick: 5064, then 5128
    assert list(kills["frame_index"]) == [2]
    assert list(bombs["bombAction"]) == ["plant_begin", "plant"]
    assert list(bombs["frame_index"]) == [0, 3]
    x, _, _ = expected_hammer_position("ct1", 1)
    assert damages["attackerX_m"].iloc[0] == pytest.approx(x * HAMMER_TO_M)
    assert damages["distance_m"].iloc[0] == pytest.approx(500 * HAMMER_TO_M)
    assert bombs["playerZ_m"].iloc[1] == pytest.approx(BOMB_HAMMER[2] * HAMMER_TO_M)
    assert damages["attackerSteamID"].iloc[0] == int(CT_KEYS[0])
    assert bool(kills["isHeadshot"].iloc[0]) and kills["assisterSteamID"].isna().all()
    assert len(match.round(1).damages) == 0
    assert list(match.round(1).damages.columns) == list(damages.columns)


def test_round_without_frames(match: Match) -> None:
    played = match.round(3)
    assert played.num_frames == 0 and played.num_players == 0
    assert played.position.shape == (0, 0, 3) and played.bomb_position.shape == (0, 3)
    damage = played.damages.iloc[0]
    assert damage["weapon"] == "World" and damage["frame_index"] == -1
    assert np.isnan(damage["attackerX_m"]) and np.isnan(damage["distance_m"])
    assert played.winning_side == "CT" and played.end_reason == "CTWin"
    assert (played.start_tick, played.end_tick) == (8000, 12000)
    assert played.side_indices("T").size == 0


def test_round_ticks_fall_back_to_frames(tmp_path: Path) -> None:
    document = make_match()
    document["gameRounds"][0].update(startTick=None, endTick=None, roundNum=None)
    played = read_match(_write(tmp_path, document)).round(1)  # null roundNum: position 1
    assert (played.start_tick, played.end_tick) == (ROUND1_TICKS[0], ROUND1_TICKS[-1])


def test_empty_side_and_null_team(tmp_path: Path) -> None:
    document = make_match()
    for frame in document["gameRounds"][0]["frames"]:
        frame["ct"]["players"] = []
    document["gameRounds"][1]["frames"][0]["ct"] = None
    result = read_match(_write(tmp_path, document))
    assert result.round(1).side_indices("CT").size == 0
    assert result.round(1).num_players == 5
    assert not result.round(2).present[result.round(2).side_indices("CT"), 0].any()


def test_side_indices_rejects_other_names(match: Match) -> None:
    with pytest.raises(ValueError, match="side must be"):
        match.round(1).side_indices("ct")  # type: ignore[arg-type]


def test_missing_round_names_the_range(match: Match, match_file: Path) -> None:
    with pytest.raises(EstaError, match=r"no round 7 \(rounds 1-3\)") as caught:
        match.round(7)
    assert str(match_file) in str(caught.value)


# --- file-level problems ------------------------------------------------------------------


def test_missing_file_and_folder(tmp_path: Path) -> None:
    assert "no such file" in _file_error(tmp_path / "absent.json.xz")
    assert "is a folder" in _file_error(tmp_path)


def test_truncated_and_corrupt_xz(tmp_path: Path) -> None:
    data = lzma.compress(encode(make_match()))
    truncated = tmp_path / "truncated.json.xz"
    truncated.write_bytes(data[: len(data) // 2])
    assert "corrupt or truncated xz" in _file_error(truncated)
    corrupt = tmp_path / "corrupt.json.xz"
    middle = len(data) // 2
    corrupt.write_bytes(data[:middle] + bytes(b ^ 0xFF for b in data[middle : middle + 64]))
    assert "corrupt or truncated xz" in _file_error(corrupt)


@pytest.mark.parametrize(
    ("data", "expected"),
    [
        (b'{"gameRounds": [', "invalid JSON"),
        (b"", "invalid JSON"),
        (b"\xff\xfe{}", "invalid JSON"),
        (b'{"\xe3x": 1, "gameRounds": []}', "invalid JSON ('utf-8' codec can't decode"),
        (b"[1, 2]", "the JSON is not an object"),
        (b'{"matchID": "x", "tickRate": 128}', "no gameRounds"),
        (b'{"gameRounds": {"a": 1}, "tickRate": 128}', "gameRounds is not a list"),
        (b'{"gameRounds": [], "tickRate": "128"}', "tickRate '128' is not a number"),
        (b'{"gameRounds": [], "tickRate": null}', "tickRate None is not a number"),
        (b'{"gameRounds": [], "tickRate": -64}', "tickRate -64 is not a positive integer"),
        (b'{"gameRounds": [], "tickRate": 128, "mapName": 5}', "mapName 5 is not a string"),
        (b'{"gameRounds": [], "tickRate": 128, "matchID": [1]}', "matchID [1] is not a string"),
        (
            b'{"gameRounds": [{"roundNum": 1}, {"roundNum": 1.0}], "tickRate": 128}',
            "round 1 appears twice",
        ),
        (b'{"gameRounds": [], "tickRate": 128, "x": 1e999}', "unreadable top-level metadata"),
    ],
)
def test_file_level_errors(tmp_path: Path, data: bytes, expected: str) -> None:
    path = tmp_path / "bad.json"
    path.write_bytes(data)
    assert expected in _file_error(path)


def test_nan_literal_position_names_round_frame_player(tmp_path: Path) -> None:
    document = make_match()
    frame = document["gameRounds"][1]["frames"][4]
    victim = next(p for p in frame["t"]["players"] if p["name"] == "t2")
    victim["y"] = float("nan")  # json writes the NaN literal msgspec rejects
    message = _round_error(tmp_path, document, 2)
    assert f"frame 4 (tick {ROUND2_TICKS[4]}): player {T_KEYS[1]} position" in message
    assert "NaN or off the map" in message


def test_off_map_position(tmp_path: Path) -> None:
    document = make_match()
    player = document["gameRounds"][0]["frames"][2]["ct"]["players"][0]
    player["x"] = 17_000.0  # beyond the engine's world (de_vertigo's z of 11,500 u is not)
    message = _round_error(tmp_path, document, 1)
    assert (
        f"frame 2 (tick {ROUND1_TICKS[2]}): player {player['steamID']} position (17000.0" in message
    )


def test_null_position_counts_as_absent(tmp_path: Path) -> None:
    document = make_match()
    player = document["gameRounds"][0]["frames"][1]["t"]["players"][0]
    player["z"] = None
    played = read_match(_write(tmp_path, document)).round(1)
    row = _row(played, str(player["steamID"]) if player["steamID"] else player["name"])
    assert not played.present[row, 1] and played.present[row, 0]


def test_off_map_bomb_and_event(tmp_path: Path) -> None:
    document = make_match()
    document["gameRounds"][1]["frames"][3]["bomb"]["z"] = -20_000
    assert "frame 3 (tick 5192): bomb position" in _round_error(tmp_path, document, 2)
    document = make_match()
    document["gameRounds"][2]["damages"][0]["victimX"] = float("inf")
    assert "damages[0]: victimX inf u is off the map" in _round_error(tmp_path, document, 3)


def test_unknown_weapon_in_frame_and_event(tmp_path: Path) -> None:
    document = make_match()
    document["gameRounds"][0]["frames"][3]["t"]["players"][0]["activeWeapon"] = "Railgun"
    assert "unknown weapon 'Railgun'" in _round_error(tmp_path, document, 1)
    document = make_match()
    document["gameRounds"][1]["kills"][0]["weapon"] = "Banana"
    assert "kills[0]: unknown weapon 'Banana'" in _round_error(tmp_path, document, 2)


@pytest.mark.parametrize(
    ("change", "expected"),
    [
        (
            lambda r: r["frames"][1]["t"]["players"][2].update(hp="full"),
            "got `str` at `frames[1].t.players[2].hp`",
        ),
        (
            lambda r: r["frames"][0].update(t=[1, 2]),
            "expected `object | null`, got `array` at `frames[0].t`",
        ),
        (lambda r: r.update(frames={"0": {}}), "got `object` at `frames`"),
        (lambda r: r["frames"][2].update(tick=None), "frame 2 has no valid tick (None)"),
        (lambda r: r["frames"][2].update(tick=10.5), "frame 2 has no valid tick (10.5)"),
        (lambda r: r["frames"][3].update(tick=0), "frame 3 (tick 0) comes before frame 2"),
        (lambda r: r.update(winningSide="Terrorists"), "winningSide 'Terrorists' is not T or CT"),
        (lambda r: r.update(bombPlantTick=1.5), "bombPlantTick 1.5 is not an integer"),
        (lambda r: r["frames"][0]["t"]["players"][1].update(hp=-5), "hp -5 is out of range"),
        (
            lambda r: r["frames"][0]["t"]["players"][1].update(steamID=1.5),
            "steamID 1.5 is not an integer",
        ),
        (
            lambda r: r["frames"][0]["t"]["players"][1].update(steamID=None, name=None),
            "neither steamID nor name",
        ),
        (
            lambda r: r["frames"][0]["t"]["players"].append(
                dict(r["frames"][0]["t"]["players"][0])
            ),
            "appears twice",
        ),
        (
            lambda r: r["frames"][0]["ct"]["players"].append(
                dict(r["frames"][0]["t"]["players"][0])
            ),
            "t1 is listed for T and for CT (a player keeps one side within a round)",
        ),
        (
            lambda r: r["damages"].append({"tick": 5000, "hpDamage": 2.5}),
            "damages[2]: hpDamage 2.5 is not an integer",
        ),
        (
            lambda r: r["damages"].append({"victimSteamID": 1e300}),
            "victimSteamID 1e+300 is not a steamID",
        ),
    ],
)
def test_round_level_errors(tmp_path: Path, change: Any, expected: str) -> None:
    document = make_match()
    change(document["gameRounds"][1])
    assert expected in _round_error(tmp_path, document, 2)


def test_invalid_utf8_inside_a_round_fails_that_round(tmp_path: Path) -> None:
    data = encode(make_match()).replace(b'"TargetBombed"', b'"Target\xe3Bombed"')
    path = tmp_path / "bad.json"
    path.write_bytes(data)
    result = read_match(path)
    assert list(result.round_errors) == [2]
    assert "'utf-8' codec can't decode" in str(result.round_errors[2])


def test_round_that_is_not_an_object_fails_alone(tmp_path: Path) -> None:
    document = make_match()
    document["gameRounds"][2] = "round three"
    assert "expected `object`, got `str`" in _round_error(tmp_path, document, 3)


# --- addressing ---------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("address", "expected"),
    [
        ("m.json.xz:3", (Path("m.json.xz"), 3)),
        ("data/odd:name.json:12", (Path("data/odd:name.json"), 12)),
        ("C:/matches/m.json.xz:0", (Path("C:/matches/m.json.xz"), 0)),
    ],
)
def test_parse_round_address(address: str, expected: tuple[Path, int]) -> None:
    assert parse_round_address(address) == expected


@pytest.mark.parametrize(
    "address", ["m.json.xz", "m.json.xz:", ":3", "m.json:x", "m.json:-1", "m:3.0", "m:٣"]
)
def test_parse_round_address_rejects(address: str) -> None:
    with pytest.raises(EstaError, match="expected FILE:ROUND"):
        parse_round_address(address)


def test_iter_match_files(tmp_path: Path) -> None:
    for name in ("b.json.xz", "a.json", "notes.txt", "c.xz"):
        (tmp_path / name).write_bytes(b"{}")
    (tmp_path / "sub.json").mkdir()
    assert iter_match_files(tmp_path) == [tmp_path / "a.json", tmp_path / "b.json.xz"]
    assert iter_match_files(tmp_path / "notes.txt") == [tmp_path / "notes.txt"]
    with pytest.raises(EstaError, match="no such file or folder"):
        iter_match_files(tmp_path / "absent")
    (tmp_path / "empty").mkdir()
    with pytest.raises(EstaError, match="no match files in this folder"):
        iter_match_files(tmp_path / "empty")


def test_load_round(match_file: Path) -> None:
    assert load_round(f"{match_file}:2").bomb_plant_tick == ROUND2_PLANT_TICK
    with pytest.raises(EstaError, match="no round 9"):
        load_round(f"{match_file}:9")


# --- decoy info ---------------------------------------------------------------------------


def test_info_match(match_file: Path) -> None:
    result = runner.invoke(app, ["info", str(match_file)])
    assert result.exit_code == 0, result.output
    assert f"{MATCH_ID}: de_dust2, 128 tick" in result.output
    assert "TargetBombed" in result.output and str(ROUND2_PLANT_TICK) in result.output


def test_info_round(match_file: Path) -> None:
    result = runner.invoke(app, ["info", f"{match_file}:1"])
    assert result.exit_code == 0, result.output
    assert "4 frames" in result.output
    for key in ("t4", "BOT t5", "ct4"):
        assert key in result.output
    ct4_line = next(line for line in result.output.splitlines() if "ct4" in line)
    assert ct4_line.split("│")[4].strip() == "3"  # present in 3 of 4 frames


def test_info_folder(tmp_path: Path) -> None:
    write_match(tmp_path / "one.json.xz")
    write_match(tmp_path / "two.json")
    result = runner.invoke(app, ["info", str(tmp_path)], env={"COLUMNS": "200"})
    assert result.exit_code == 0, result.output
    assert "one.json.xz" in result.output and "two.json" in result.output
    assert result.output.count("de_dust2") == 2


def test_info_folder_with_a_bad_file_fails(tmp_path: Path) -> None:
    write_match(tmp_path / "good.json.xz")
    (tmp_path / "bad.json").write_text("not json")
    result = runner.invoke(app, ["info", str(tmp_path)], env={"COLUMNS": "200"})
    assert result.exit_code == 1
    assert result.stderr.strip() == (
        f"error: {tmp_path}: 1 of 2 match files are unreadable, 0 rounds failed "
        "(`decoy info FILE` says why)"
    )
    assert "good.json.xz" in result.stdout


def test_info_folder_with_a_failed_round_fails_as_for_one_file(tmp_path: Path) -> None:
    document = make_match()
    document["gameRounds"][1]["frames"] = "not a list"
    write_match(tmp_path / "broken.json", document)
    write_match(tmp_path / "good.json.xz")
    result = runner.invoke(app, ["info", str(tmp_path)], env={"COLUMNS": "200"})
    assert result.exit_code == 1
    assert result.stderr.strip() == (
        f"error: {tmp_path}: 0 of 2 match files are unreadable, 1 rounds failed "
        "(`decoy info FILE` says why)"
    )


def test_info_match_with_a_bad_round_fails(tmp_path: Path) -> None:
    document = make_match()
    document["gameRounds"][0]["frames"][0]["t"]["players"][0]["x"] = 1e6
    path = _write(tmp_path, document)
    result = runner.invoke(app, ["info", str(path)], env={"COLUMNS": "200"})
    assert result.exit_code == 1
    assert "off the map" in result.stdout
    assert result.stderr.strip() == f"error: {path}: 1 of 3 rounds are unreadable"


@pytest.mark.parametrize(
    ("argument", "expected"),
    [
        ("{dir}/absent.json.xz", "error: {dir}/absent.json.xz: no such file or folder"),
        ("{dir}/absent.json.xz:3", "error: {dir}/absent.json.xz: no such file"),
        ("{file}:9", "error: {file}: no round 9 (rounds 1-3)"),
        ("{file}:x", "error: {file}:x: no such file or folder"),
    ],
)
def test_info_errors_are_one_line(match_file: Path, argument: str, expected: str) -> None:
    values = {"dir": match_file.parent, "file": match_file}
    result = runner.invoke(app, ["info", argument.format(**values)])
    assert result.exit_code == 1
    assert result.stderr == expected.format(**values) + "\n"
    assert result.stdout == ""


def test_info_corrupt_file(tmp_path: Path) -> None:
    path = tmp_path / "cut.json.xz"
    path.write_bytes(lzma.compress(encode(make_match()))[:100])
    result = runner.invoke(app, ["info", str(path)])
    assert result.exit_code == 1
    assert result.stderr.startswith(f"error: {path}: corrupt or truncated xz")
    assert result.stderr.count("\n") == 1


# --- the real shared data -----------------------------------------------------------------


@pytest.fixture(scope="module")
def tside_matches() -> list[Match]:
    if not TSIDE.is_dir():
        pytest.skip(f"real ESTA data not found at {TSIDE} (../shared/data next to the repo)")
    return [read_match(path) for path in iter_match_files(TSIDE)]


def test_real_tside_files(tside_matches: list[Match]) -> None:
    assert len(tside_matches) == 15
    assert sum(len(m.rounds) for m in tside_matches) == 385
    assert all(not m.round_errors and m.map_name == "de_dust2" for m in tside_matches)
    assert all(m.tick_rate == 128 and "provenance" in m.meta for m in tside_matches)
    for played in (r for m in tside_matches for r in m.rounds):
        assert played.side_indices("CT").size == 0
        assert [p.key for p in played.players] == [f"T-slot-{i}" for i in range(5)]
        assert played.present.all()
        positions = played.position[played.present]
        assert np.isfinite(positions).all()
        assert np.abs(positions[:, :2]).max() < 4_000 * HAMMER_TO_M  # de_dust2 is about ±3,500 u
        assert (np.diff(played.frame_ticks) > 0).all()
        assert played.damages.empty and played.winning_side is None


def test_real_events_file() -> None:
    if not EVENTS.is_file():
        pytest.skip(
            f"real ESTA events file not found at {EVENTS} (../shared/data next to the repo)"
        )
    real = read_match(EVENTS)
    assert not real.round_errors and [r.round_num for r in real.rounds] == list(range(1, 19))
    assert sum(len(r.damages) for r in real.rounds) == 503
    assert all(r.num_frames == 0 for r in real.rounds)
    assert all((r.damages["frame_index"] == -1).all() for r in real.rounds)
    assert {r.winning_side for r in real.rounds} == {"T", "CT"}
    damages = [r.damages for r in real.rounds]
    assert sum(int((d["weapon"] == "World").sum()) for d in damages) == 2
    assert sum(int(d["attackerSteamID"].isna().sum()) for d in damages) >= 2


def test_real_folder_info() -> None:
    if not TSIDE.is_dir():
        pytest.skip(f"real ESTA data not found at {TSIDE} (../shared/data next to the repo)")
    result = runner.invoke(app, ["info", str(TSIDE)], env={"COLUMNS": "200"})
    assert result.exit_code == 0, result.output
    assert result.stdout.count("de_dust2") == 15
    assert "00e7fec9-cee0-430f-80f4-6b50443ceacd.json.xz" in result.stdout


def test_the_round_clock_is_the_games_whatever_rate_the_file_wrote_seconds_at(
    tmp_path: Path,
) -> None:
    """Some awpy 1.x exports wrote `seconds` at 127 per second on 128-tick demos: the reader
    keeps the game's clock (ticks at tickRate), placing only its zero by the file's seconds;
    events get the same clock."""
    document = make_match()
    round2 = document["gameRounds"][1]
    round2["freezeTimeEndTick"] = None
    for frame in round2["frames"]:
        frame["seconds"] = (frame["tick"] - ROUND2_FREEZE_END) / 127
    for event in round2["bombEvents"]:
        event["seconds"] = (event["tick"] - ROUND2_FREEZE_END) / 127
    played = read_match(write_match(tmp_path / "slow.json", document)).round(2)
    ticks = np.asarray(played.frame_ticks, dtype=float)
    assert np.allclose(played.frame_seconds, (ticks - ROUND2_FREEZE_END) / 128)
    assert played.clock is not None and played.clock.zero_tick == pytest.approx(ROUND2_FREEZE_END)
    events = played.bomb_events
    assert np.allclose(events["seconds"], (events["tick"].astype(float) - ROUND2_FREEZE_END) / 128)


def test_vertical_speed_in_metres_per_second_nan_where_null(tmp_path: Path) -> None:
    document = make_match()
    frames = document["gameRounds"][0]["frames"]
    name = frames[1]["t"]["players"][0]["name"]
    for frame, value in ((1, -250.0), (2, None)):  # player order changes from frame to frame
        for player in frames[frame]["t"]["players"]:
            if player["name"] == name:
                player["velocityZ"] = value
    played = read_match(write_match(tmp_path / "m.json.xz", document)).round(1)
    row = [p.name for p in played.players].index(name)
    assert played.vertical_speed[row, 1] == pytest.approx(-250.0 * HAMMER_TO_M)
    assert np.isnan(played.vertical_speed[row, 2])
    assert played.vertical_speed[row, 0] == 0.0  # on the ground
    missing = [p.name for p in played.players].index(MISSING_CT[0])
    assert np.isnan(played.vertical_speed[missing, MISSING_CT[2]])


@pytest.mark.parametrize("value", [1e9, -4000.0])
def test_a_vertical_speed_beyond_the_engine_cap_fails_the_round(
    tmp_path: Path, value: float
) -> None:
    document = make_match()
    document["gameRounds"][0]["frames"][1]["t"]["players"][0]["velocityZ"] = value
    match = read_match(write_match(tmp_path / "m.json.xz", document))
    assert 1 not in [r.round_num for r in match.rounds]
    assert "velocityZ" in str(match.round_errors[1])
