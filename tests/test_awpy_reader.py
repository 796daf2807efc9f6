"""CS2 rounds from awpy's tables (decoy_cli/esta/awpy/): the real rounds of ../shared/data in both
layouts read as their ESTA-shaped file, the project's synthetic sample written in both layouts
and read back with what the real rounds lack, the names, the rate, and bad input."""

from __future__ import annotations

import io
import json
import os
import re
import sys
import zipfile
from dataclasses import replace
from pathlib import Path

import numpy as np
import pandas as pd
import pyarrow as pa
import pyarrow.parquet as pq
import pytest
from typer.testing import CliRunner

from decoy_cli.cli import app
from decoy_cli.errors import EstaError
from decoy_cli.esta import Match, Round, read_match
from decoy_cli.esta.awpy.names import bomb_action, end_reason, hit_group, side_name, weapon_name
from decoy_cli.esta.awpy.writer import write_awpy2_zip, write_awpy3_folder
from decoy_cli.esta.reader import UTILITY_COLUMNS
from decoy_cli.replay.missing import fill_missing, lacking
from decoy_cli.sim.rules import RulesConfig
from decoy_cli.sim.sites import SiteZones
from decoy_cli.waypoints.build import builtin_graph

ROOT = Path(__file__).resolve().parents[1]
SHARED = ROOT.parent / "shared" / "data"
SAMPLE = ROOT / "examples" / "sample" / "synthetic-dust2-seed0.json.xz"
STEMS = ("spirit-vs-falcons-m2-dust2-r01-12", "spirit-vs-falcons-m2-dust2-8hz-r02")
needs_data = pytest.mark.skipif(
    not (SHARED / "cs2_dust2_awpy").is_dir(),
    reason="../shared/data/cs2_dust2_awpy is absent (the real CS2 rounds in awpy's layouts)",
)
FLOAT32_M = 2e-3 * 0.01905
"""Most a float32 Hammer coordinate of de_dust2 (|x| < 4,096 u) lies from a decimal, in metres."""


def _forms(stem: str) -> tuple[Match, Match, Match]:
    return (
        read_match(SHARED / "cs2_dust2_both" / f"{stem}.json.xz"),
        read_match(SHARED / "cs2_dust2_awpy" / "awpy2" / f"{stem}.zip"),
        read_match(SHARED / "cs2_dust2_awpy" / "awpy3" / stem),
    )


EXACT_FIELDS = ("frame_ticks", "frame_seconds", "hp", "alive", "present", "bomb_planted")
EVENT_COLUMNS = {
    "kills": [
        "tick", "seconds", "attackerName", "attackerSide", "attackerX", "attackerY", "victimName",
        "victimSide", "victimX", "victimY", "weapon", "isHeadshot", "isSuicide", "isTeamkill",
    ],
    "bomb_events": ["tick", "seconds", "bombAction", "bombSite", "playerName"],
}  # fmt: skip


def _assert_same_round(esta: Round, other: Round) -> None:
    for name in EXACT_FIELDS:
        np.testing.assert_array_equal(getattr(esta, name), getattr(other, name), err_msg=name)
    np.testing.assert_allclose(other.position, esta.position, atol=FLOAT32_M, rtol=0)
    np.testing.assert_array_equal(np.isnan(esta.yaw), np.isnan(other.yaw))
    np.testing.assert_allclose(other.yaw, esta.yaw, atol=1e-3, equal_nan=True)
    np.testing.assert_array_equal(esta.bombsite, other.bombsite)
    assert esta.players == other.players
    for table, columns in EVENT_COLUMNS.items():
        pd.testing.assert_frame_equal(
            getattr(esta, table)[columns].reset_index(drop=True),
            getattr(other, table)[columns].reset_index(drop=True),
            check_dtype=False,
        )
    for name in ("winning_side", "end_reason", "bomb_plant_tick", "start_tick", "end_tick"):
        assert getattr(esta, name) == getattr(other, name), name
    assert esta.clock == other.clock


@needs_data
@pytest.mark.parametrize("stem", STEMS)
def test_real_cs2_rounds_read_from_both_awpy_layouts_as_from_the_esta_shaped_file(
    stem: str,
) -> None:
    esta, awpy2, awpy3 = _forms(stem)
    assert esta.round_numbers == awpy2.round_numbers == awpy3.round_numbers
    assert not awpy2.round_errors and not awpy3.round_errors
    for round_esta, round_2, round_3 in zip(esta.rounds, awpy2.rounds, awpy3.rounds, strict=True):
        _assert_same_round(round_esta, round_2)
        _assert_same_round(round_esta, round_3)
        assert (round_2.source, round_3.source) == ("awpy 2", "awpy 3")


@needs_data
def test_what_the_real_tables_do_not_record_is_named_and_held_absent() -> None:
    _, awpy2, awpy3 = _forms(STEMS[0])
    for match in (awpy2, awpy3):
        first = match.rounds[0]  # round 1 has a plant and nobody holds the bomb
        assert {"weapon in hand", "armour, helmet and kit", "steamids", "bomb carrier"} <= set(
            first.not_recorded
        )
        assert (first.armor == -1).all() and (first.weapon == "").all()
        # awpy 3's stand-in yaw 0.0 in every row is no view: the 1 Hz file records none
        assert np.isnan(first.yaw).all()
        assert {"weapon", "armour", "bomb carrier"} <= set(lacking(first))
    assert "tick rate 64" not in awpy2.meta["tick_rate_rule"]  # it says which rule decided


@needs_data
def test_real_8hz_round_keeps_its_yaw_and_own_rate() -> None:
    esta, awpy2, awpy3 = _forms(STEMS[1])
    for match in (awpy2, awpy3):
        round_ = match.round(2)
        assert "view angles" not in round_.not_recorded
        assert np.median(np.diff(round_.frame_ticks)) == 8  # sampled at 8 Hz: read as it is
        assert round_.num_frames == esta.round(2).num_frames


def _sample() -> Match:
    return read_match(SAMPLE)


def test_the_sample_round_trips_through_both_layouts_with_what_the_real_rounds_lack(
    tmp_path: Path,
) -> None:
    sample = _sample()
    for match in (
        read_match(write_awpy2_zip(sample, tmp_path / "sample.zip")),
        read_match(write_awpy3_folder(sample, tmp_path / "sample")),
    ):
        assert match.tick_rate == 128 and match.map_name == "de_dust2"
        for esta, other in zip(sample.rounds, match.rounds, strict=True):
            for name in ("weapon", "armor", "helmet", "has_defuser", "has_bomb", "hp", "alive"):
                np.testing.assert_array_equal(getattr(esta, name), getattr(other, name), name)
            np.testing.assert_allclose(other.position, esta.position, atol=FLOAT32_M, rtol=0)
            turn = (other.yaw - esta.yaw + 180.0) % 360.0 - 180.0
            assert np.nanmax(np.abs(turn)) < 1e-3
            assert [p.steam_id for p in other.players] == [p.steam_id for p in esta.players]
            kills = ["tick", "attackerName", "victimName", "weapon", "isHeadshot"]
            pd.testing.assert_frame_equal(esta.kills[kills], other.kills[kills], check_dtype=False)
            damages = ["tick", "weapon", "hpDamage", "hpDamageTaken", "hitGroup", "armorDamage"]
            pd.testing.assert_frame_equal(
                esta.damages[damages], other.damages[damages], check_dtype=False
            )
            assert other.not_recorded == ("vertical speed", "utility (smokes, fires, blinds)")
            assert "weapon" not in lacking(other) and "armour" not in lacking(other)


def test_awpy2_reads_the_carrier_from_the_inventory_and_the_rate_from_the_bomb_timer(
    tmp_path: Path,
) -> None:
    match = read_match(write_awpy2_zip(_sample(), tmp_path / "sample.zip"))
    assert match.tick_rate == 128
    assert "40 s" in match.meta["tick_rate_rule"]
    assert all(r.has_bomb.any() for r in match.rounds)


def test_awpy3_takes_the_defuse_start_from_is_defusing_and_awpy2_infers_it(
    tmp_path: Path,
) -> None:
    sample = _sample()
    esta = sample.round(1).bomb_events
    real_start = int(esta.loc[esta["bombAction"] == "defuse_start", "tick"].iloc[0])
    awpy3 = read_match(write_awpy3_folder(sample, tmp_path / "sample")).round(1)
    starts = awpy3.bomb_events.loc[awpy3.bomb_events["bombAction"] == "defuse_start", "tick"]
    assert 0 <= int(starts.iloc[0]) - real_start < 64  # the first frame showing the defuse
    assert "defuse start" not in lacking(awpy3)

    awpy2 = read_match(write_awpy2_zip(sample, tmp_path / "sample.zip")).round(1)
    assert "defuse start" in lacking(awpy2)  # awpy 2 writes no begin-defuse row
    graph = builtin_graph("de_dust2")
    filled = fill_missing(awpy2, SiteZones.from_graph(graph), RulesConfig(), "infer")
    events = filled.round.bomb_events
    start = events.loc[events["bombAction"] == "defuse_start", "tick"].iloc[0]
    defuse = events.loc[events["bombAction"] == "defuse", "tick"].iloc[0]
    assert defuse - start == RulesConfig().defuse_s * 128  # CT-2 holds no kit
    assert start == real_start  # the sample's defuser took the rules' 10 s
    assert any(note.startswith("defuse start (CT-2)") for note in filled.notes)


def test_full_rate_ticks_are_sampled_on_a_grid_from_freeze_end(tmp_path: Path) -> None:
    sample = _sample()
    two = replace(sample, rounds=sample.rounds[:2])
    path = write_awpy3_folder(two, tmp_path / "full", every=1)
    for rate, step in ((8.0, 16), (2.0, 64)):
        match = read_match(path, rate=rate)
        for esta, round_ in zip(two.rounds, match.rounds, strict=True):
            assert (np.diff(round_.frame_ticks) == step).all()
            assert round_.frame_ticks[0] == esta.clock.zero_tick
    # at the sample's own 2 Hz the frames are the sample's, positions as written
    match = read_match(path, rate=2.0)
    for esta, round_ in zip(two.rounds, match.rounds, strict=True):
        np.testing.assert_array_equal(esta.frame_ticks, round_.frame_ticks)
        np.testing.assert_allclose(round_.position, esta.position, atol=FLOAT32_M, rtol=0)


@pytest.mark.parametrize(
    ("raw", "spelling", "esta"),
    [
        ("m4a1", "item", "M4A4"),
        ("m4a1_silencer", "item", "M4A1"),
        ("weapon_m4a1_silencer", "item", "M4A1"),
        ("M4A1-S", "display", "M4A1"),
        ("M4A4", "display", "M4A4"),
        ("usp_silencer", "item", "USP-S"),
        ("hkp2000", "item", "P2000"),
        ("USP-S", "display", "USP-S"),
        ("P2000", "display", "P2000"),
        ("deagle", "item", "Desert Eagle"),
        ("revolver", "item", "R8 Revolver"),
        ("R8 Revolver", "display", "R8 Revolver"),
        ("CZ75-Auto", "display", "CZ75 Auto"),
        ("cz75a", "item", "CZ75 Auto"),
        ("knife_karambit", "item", "Knife"),
        ("Butterfly Knife", "display", "Knife"),
        ("C4 Explosive", "display", "C4"),
        ("planted_c4", "item", "C4"),
        ("inferno", "item", "Incendiary Grenade"),
        ("taser", "item", "Zeus x27"),
        ("world", "item", "World"),
        (None, "item", ""),
        ("laser_rifle", "item", None),
        ("m4a1_silencer", "display", None),  # an item name where display names are due
    ],
)
def test_weapon_names_across_the_sources(raw: object, spelling: str, esta: str | None) -> None:
    assert weapon_name(raw, spelling) == esta  # type: ignore[arg-type]


def test_other_names_across_the_sources() -> None:
    assert [side_name(s) for s in ("t", "ct", "terrorist", "counter-terrorist", 2, 3, "spec")] == [
        "T", "CT", "T", "CT", "T", "CT", None,
    ]  # fmt: skip
    assert [hit_group(h) for h in ("head", "left_arm", 1, 8, "invalid", -1, "elbow")] == [
        "Head", "LeftArm", "Head", "Neck", "", "", None,
    ]  # fmt: skip
    assert [end_reason(r) for r in ("t_killed", "ct_win", 9, "bomb_exploded", 1, "x")] == [
        "CTWin", "CTWin", "TerroristsWin", "TargetBombed", "TargetBombed", None,
    ]  # fmt: skip
    assert [bomb_action(e) for e in ("detonate", "finish_plant", "start_plant", "pickup")] == [
        "explode", "plant", "plant_begin", None,
    ]  # fmt: skip


# --- bad input: one error line, or the round's named failure or warning -------------------------


def _edit_table(folder: Path, name: str, edit) -> None:  # type: ignore[no-untyped-def]
    path = folder / f"{name}.parquet"
    pq.write_table(edit(pq.read_table(path)), path)


@pytest.fixture
def folder(tmp_path: Path) -> Path:
    sample = _sample()
    return write_awpy3_folder(replace(sample, rounds=sample.rounds[:2]), tmp_path / "m")


def test_a_missing_table_is_named(folder: Path) -> None:
    (folder / "kills.parquet").unlink()
    with pytest.raises(EstaError, match="no kills table"):
        read_match(folder)


def test_a_zip_without_a_table_or_header_is_named(tmp_path: Path) -> None:
    path = write_awpy2_zip(_sample(), tmp_path / "m.zip")
    with zipfile.ZipFile(path) as archive:
        kept = {n: archive.read(n) for n in archive.namelist() if n != "ticks.parquet"}
    with zipfile.ZipFile(path, "w") as archive:
        for name, data in kept.items():
            archive.writestr(name, data)
    with pytest.raises(EstaError, match="no ticks table"):
        read_match(path)
    (tmp_path / "bad.zip").write_bytes(b"PK\x03\x04 not a zip")
    with pytest.raises(EstaError, match="not a readable zip"):
        read_match(tmp_path / "bad.zip")


def test_a_column_of_the_wrong_type_is_named(folder: Path) -> None:
    def text_x(table: pa.Table) -> pa.Table:
        index = table.schema.get_field_index("x")
        return table.set_column(index, "x", pa.array([str(v) for v in table["x"].to_pylist()]))

    _edit_table(folder, "snapshots", text_x)
    with pytest.raises(EstaError, match="snapshots: column x holds"):
        read_match(folder)


def test_a_table_that_is_not_parquet_is_named(folder: Path) -> None:
    (folder / "rounds.parquet").write_bytes(b"PAR1 garbage")
    with pytest.raises(EstaError, match="rounds: not a readable parquet table"):
        read_match(folder)


def test_ticks_of_another_demo_are_refused(folder: Path) -> None:
    _edit_table(
        folder,
        "snapshots",
        lambda t: t.set_column(0, "tick", pa.compute.add(t["tick"], pa.scalar(10**7, pa.int32()))),
    )
    with pytest.raises(EstaError, match="falls in a round of its rounds table"):
        read_match(folder)


def test_a_player_twice_at_one_tick_fails_the_round_and_unsorted_ticks_warn(
    folder: Path,
) -> None:
    table = pq.read_table(folder / "snapshots.parquet")
    pq.write_table(pa.concat_tables([table, table.slice(0, 1)]), folder / "snapshots.parquet")
    match = read_match(folder)
    assert "appears twice" in str(match.round_errors[1])
    pq.write_table(table.take(np.arange(table.num_rows)[::-1]), folder / "snapshots.parquet")
    match = read_match(folder)
    assert not match.round_errors
    assert any("not in tick order" in w for w in match.round(1).warnings)


def test_a_multipart_demo_is_refused_and_a_128_tick_header_is_taken(folder: Path) -> None:
    header = json.loads((folder / "header.json").read_text())
    assert read_match(folder).tick_rate == 128  # playback_ticks / playback_time
    (folder / "header.json").write_text(json.dumps({**header, "playback_ticks": 3333}))
    with pytest.raises(EstaError, match=r"a tick rate of 33\.33"):
        read_match(folder)
    (folder / "header.json").write_text(json.dumps(header))
    _edit_table(
        folder, "snapshots", lambda t: t.append_column("part", pa.array(np.arange(len(t)) % 2))
    )
    with pytest.raises(EstaError, match="multipart demo"):
        read_match(folder)


def test_an_unknown_weapon_is_a_named_warning(folder: Path) -> None:
    def rename(table: pa.Table) -> pa.Table:
        index = table.schema.get_field_index("active_weapon")
        weapons = ["laser_rifle" if w == "glock" else w for w in table["active_weapon"].to_pylist()]
        return table.set_column(index, "active_weapon", pa.array(weapons, pa.large_string()))

    _edit_table(folder, "snapshots", rename)
    warnings = read_match(folder).round(1).warnings
    assert any("unknown weapon in hand 'laser_rifle'" in w for w in warnings)


def test_a_header_that_is_not_a_json_object_is_named(folder: Path) -> None:
    (folder / "header.json").write_text("[1, 2]")
    with pytest.raises(EstaError, match="not a JSON object"):
        read_match(folder)


def test_a_demo_without_awpy3_installed_says_how_to_read_it(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setitem(sys.modules, "awpy", None)  # as if awpy 3 were not installed
    (tmp_path / "match.dem").write_bytes(b"PBDEMS2\x00")
    with pytest.raises(EstaError, match=r"needs awpy 3 \(pip install 'decoy\[cs2\]'\)"):
        read_match(tmp_path / "match.dem")


@pytest.mark.skipif(
    not os.environ.get("DECOY_TEST_DEMO"),
    reason="DECOY_TEST_DEMO names no CS2 demo (.dem) to read through awpy 3",
)
def test_a_real_demo_reads_through_awpy3() -> None:
    match = read_match(os.environ["DECOY_TEST_DEMO"])
    assert match.rounds and match.map_name
    assert all(r.num_frames and r.players for r in match.rounds)


@needs_data
def test_info_lists_what_awpy_tables_record_and_not() -> None:
    result = CliRunner().invoke(
        app, ["info", str(SHARED / "cs2_dust2_awpy" / "awpy2" / f"{STEMS[0]}.zip")]
    )
    assert result.exit_code == 0, result.output
    assert "(awpy 2)" in result.output and "not recorded:" in result.output
    assert "weapon in hand" in result.output


def test_zip_members_are_read_by_name_whatever_their_column_order(tmp_path: Path) -> None:
    path = write_awpy2_zip(_sample(), tmp_path / "m.zip")
    with zipfile.ZipFile(path) as archive:
        members = {n: archive.read(n) for n in archive.namelist()}
    ticks = pq.read_table(io.BytesIO(members["ticks.parquet"]))
    reordered = ticks.select(list(reversed(ticks.column_names)))
    sink = pa.BufferOutputStream()
    pq.write_table(reordered, sink)
    members["ticks.parquet"] = sink.getvalue().to_pybytes()
    with zipfile.ZipFile(path, "w") as archive:
        for name, data in members.items():
            archive.writestr(name, data)
    again = read_match(path)
    np.testing.assert_array_equal(again.round(1).hp, _sample().round(1).hp)


def test_a_rounds_table_with_a_null_tick_is_named(folder: Path) -> None:
    def null_end(table: pa.Table) -> pa.Table:
        index = table.schema.get_field_index("end_tick")
        return table.set_column(index, "end_tick", pa.array([None] * len(table), pa.int32()))

    _edit_table(folder, "rounds", null_end)
    with pytest.raises(EstaError, match="rounds: end null is not a tick"):
        read_match(folder)


def test_a_round_of_an_unknown_map_reads_and_fails_to_replay_by_name(
    folder: Path, tmp_path: Path
) -> None:
    header = json.loads((folder / "header.json").read_text())
    (folder / "header.json").write_text(json.dumps({**header, "map_name": "de_nowhere"}))
    assert read_match(folder).map_name == "de_nowhere"
    result = CliRunner().invoke(
        app, ["replay", f"{folder}:1", "--no-combat", "--out", str(tmp_path / "out")]
    )
    assert result.exit_code == 1
    assert "de_nowhere" in result.output and "Traceback" not in result.output


@needs_data
def test_replay_of_a_zip_round_matches_the_esta_shaped_file(tmp_path: Path) -> None:
    """The 8 Hz round is identical in every form (its positions are float32 in the source), on
    CS2's world as on CS:GO's (the test of CS:GO's: replay_fingerprints.py --cs2-forms)."""
    outputs = []
    for path in (
        SHARED / "cs2_dust2_both" / f"{STEMS[1]}.json.xz",
        SHARED / "cs2_dust2_awpy" / "awpy2" / f"{STEMS[1]}.zip",
    ):
        out = tmp_path / path.name
        args = ["replay", f"{path}:2", "--seed", "3", "--out", str(out), "--world", "cs2"]
        result = CliRunner().invoke(app, args)
        assert result.exit_code == 0, result.output
        summary = json.loads(next(out.rglob("summary.json")).read_text())
        assert summary["world"].startswith("CS2 de_dust2 nav mesh")
        outputs.append((summary["outcome_replay"], pd.read_csv(next(out.rglob("players.csv")))))
    assert outputs[0][0] == outputs[1][0]
    pd.testing.assert_frame_equal(outputs[0][1], outputs[1][1])


def test_a_round_replays_on_cs_go_s_world_unless_told_otherwise(tmp_path: Path) -> None:
    zipped = write_awpy2_zip(_sample(), tmp_path / "m.zip")
    for world, expected in ((["--world", "cs2"], "world: CS2 de_dust2"), ([], "world: built-in")):
        out = tmp_path / f"out{len(world)}"
        args = ["replay", f"{zipped}:1", "--no-combat", "--no-bomb", "--out", str(out), *world]
        result = CliRunner().invoke(app, args, env={"COLUMNS": "200"})
        assert result.exit_code == 0, result.output
        assert expected in result.output
    both = ["replay", f"{zipped}:1", "--graph", str(tmp_path / "g.npz"), "--world", "cs2"]
    result = CliRunner().invoke(app, both)
    assert result.exit_code == 1 and "leave out --world" in result.output


def test_sides_swap_at_halftime_by_round_and_players_keep_their_steamids(tmp_path: Path) -> None:
    sample = _sample()
    first, second = sample.rounds[:2]
    swapped_players = [
        replace(p, side="CT" if p.side == "T" else "T") for p in second.players
    ]  # the second half: the same people on the other side
    swapped = replace(second, players=swapped_players, winning_side="T", end_reason="TargetBombed")
    match = read_match(write_awpy3_folder(replace(sample, rounds=[first, swapped]), tmp_path / "m"))
    before, after = match.round(1), match.round(2)
    side_before = {p.steam_id: p.side for p in before.players}
    side_after = {p.steam_id: p.side for p in after.players}
    assert side_before.keys() == side_after.keys()
    assert all(side_before[k] != side_after[k] for k in side_before)


def _with_utility(match: Match) -> Match:
    """The sample's first round with a smoke, a fire and a blind (made up here)."""
    round_ = match.rounds[0]
    zero = round_.clock.zero_tick
    smoke = pd.DataFrame(
        {
            "start_tick": [zero + 1280.0],
            "end_tick": [zero + 1280.0 + 20 * 128],
            "x_m": [10.0],
            "y_m": [20.0],
            "z_m": [1.0],
            "thrower_name": ["T-1"],
            "thrower_side": ["T"],
            "thrower_steamid": pd.array([11], dtype="Int64"),
        }
    )
    smoke["start_s"] = round_.clock.seconds(smoke["start_tick"])
    smoke["end_s"] = round_.clock.seconds(smoke["end_tick"])
    fire = smoke.assign(end_tick=smoke["start_tick"] + 7 * 128, x_m=-5.0)
    fire["end_s"] = round_.clock.seconds(fire["end_tick"])
    flash = round_.flashes.iloc[0:0].copy()
    flash.loc[0, ["tick", "attackerName", "attackerSide", "playerName", "playerSide"]] = [
        int(zero + 640),
        "T-1",
        "T",
        "CT-1",
        "CT",
    ]
    flash.loc[0, ["attackerX", "attackerY", "attackerZ", "playerX", "playerY", "playerZ"]] = 0.0
    flash.loc[0, "flashDuration"] = 2.5
    first = replace(round_, smokes=smoke[list(UTILITY_COLUMNS)], fires=fire[list(UTILITY_COLUMNS)],
                    flashes=flash)  # fmt: skip
    return replace(match, rounds=[first, *match.rounds[1:2]])


def test_smokes_fires_and_blinds_are_read_with_their_windows(tmp_path: Path) -> None:
    match = _with_utility(_sample())
    expected = match.rounds[0]
    for source in (
        write_awpy3_folder(match, tmp_path / "m"),
        write_awpy2_zip(match, tmp_path / "m.zip"),
    ):
        round_ = read_match(source).round(1)
        for name in ("smokes", "fires"):
            got, want = getattr(round_, name), getattr(expected, name)
            np.testing.assert_allclose(got["start_s"], want["start_s"])
            np.testing.assert_allclose(got["end_s"], want["end_s"])
            np.testing.assert_allclose(got[["x_m", "y_m", "z_m"]], want[["x_m", "y_m", "z_m"]])
            assert got["thrower_side"].tolist() == ["T"]
        assert "utility (smokes, fires, blinds)" not in round_.not_recorded
        if source.suffix == ".zip":  # awpy 2 writes no blinds
            assert len(round_.flashes) == 0
        else:
            assert round_.flashes["playerName"].tolist() == ["CT-1"]
            assert round_.flashes["flashDuration"].tolist() == [2.5]


def test_a_smoke_without_an_end_and_a_blind_of_negative_duration_are_named(
    tmp_path: Path,
) -> None:
    folder = write_awpy3_folder(_with_utility(_sample()), tmp_path / "m")
    _edit_table(
        folder,
        "smokes",
        lambda t: t.set_column(1, "end_tick", pa.array([None] * len(t), pa.int64())),
    )
    _edit_table(
        folder,
        "blinds",
        lambda t: t.set_column(
            t.schema.get_field_index("duration"), "duration", pa.array([-1.0], pa.float32())
        ),
    )
    round_ = read_match(folder).round(1)
    assert any("a smoke bursting at tick" in w and "no end" in w for w in round_.warnings)
    assert any("lasts -1 s: left out" in w for w in round_.warnings)
    assert np.isnan(round_.smokes["end_s"]).all() and len(round_.flashes) == 0


# --- a hostile battery's classes (each was a bug line, a hang or silent garbage) ----------------


def _rezip(path: Path, members: list[tuple[zipfile.ZipInfo | str, bytes]]) -> Path:
    with zipfile.ZipFile(path, "w", zipfile.ZIP_DEFLATED) as archive:
        for info, data in members:
            archive.writestr(info, data)
    return path


def _members(path: Path) -> dict[str, bytes]:
    with zipfile.ZipFile(path) as archive:
        return {name: archive.read(name) for name in archive.namelist()}


def test_damaged_zip_members_are_one_error_line(tmp_path: Path) -> None:
    members = _members(write_awpy2_zip(_sample(), tmp_path / "good.zip"))
    corrupt = tmp_path / "corrupt.zip"
    _rezip(corrupt, list(members.items()))
    raw = bytearray(corrupt.read_bytes())
    start = raw.find(b"header.json") + len(b"header.json")  # the header's deflated bytes
    raw[start : start + 8] = b"\xff" * 8
    corrupt.write_bytes(bytes(raw))
    with pytest.raises(EstaError, match=r"header\.json cannot be read"):
        read_match(corrupt)
    with pytest.warns(UserWarning, match="Duplicate name"):  # zipfile writes it anyway
        twice = _rezip(tmp_path / "twice.zip", [*members.items(), ("header.json", b"{}")])
    with pytest.raises(EstaError, match=r"holds header\.json twice"):
        read_match(twice)


@pytest.mark.parametrize(
    ("header", "said"),
    [
        ('{"map_name": ""}', "names no map"),
        ('{"map_name": "de_dust2", "map_name": "de_mirage"}', "'map_name' is given twice"),
        ('{"map_name": "de_dust2", "playback_ticks": 6400, "playback_time": 0}', "playback_time"),
        ('{"map_name": "de_dust2", "playback_ticks": NaN, "playback_time": 100}', "playback_ticks"),
        ('{"map_name": "de_dust2", "playback_ticks": "6400", "playback_time": 100}', "playback_t"),
        ('{"map_name": "de_dust2", "tick_rate": 1' + "0" * 400 + "}", "tick_rate"),
    ],
)
def test_bad_headers_are_named(folder: Path, header: str, said: str) -> None:
    (folder / "header.json").write_text(header)
    with pytest.raises(EstaError, match=said):
        read_match(folder)


def test_a_header_rate_the_rules_deny_is_said(tmp_path: Path) -> None:
    path = write_awpy2_zip(_sample(), tmp_path / "m.zip")  # 128 tick: two bomb timers say so
    members = _members(path)
    header = json.loads(members["header.json"]) | {"tick_rate": 64}  # a header saying 64
    _rezip(path, [*((k, v) for k, v in members.items() if k != "header.json"),
                  ("header.json", json.dumps(header).encode())])  # fmt: skip
    match = read_match(path)
    assert match.tick_rate == 64 and "they deny 64 (warning)" in match.meta["tick_rate_rule"]


@pytest.mark.parametrize(
    ("table", "column", "value", "said"),
    [
        ("rounds", "start_tick", -1_000_000, "rounds: start -1000000 is not a tick"),
        ("snapshots", "tick", float("inf"), "snapshots: a row's tick inf"),
        ("kills", "tick", 1e30, "kills: a row's tick 1e\\+30"),
    ],
)
def test_ticks_no_demo_has_are_named(
    folder: Path, table: str, column: str, value: float, said: str
) -> None:
    def edit(data: pa.Table) -> pa.Table:
        values = data[column].to_pylist()
        values[0] = value
        return data.set_column(data.schema.get_field_index(column), column, pa.array(values))

    _edit_table(folder, table, edit)
    with pytest.raises(EstaError, match=said):
        read_match(folder)


def test_a_round_longer_than_any_game_fails_by_name(folder: Path) -> None:
    def stretch(data: pa.Table) -> pa.Table:
        ticks = data["tick"].to_numpy().copy()
        ticks[ticks == ticks.max()] += 128 * 700  # 700 s after the rest
        return data.set_column(0, "tick", pa.array(ticks, pa.int32()))

    _edit_table(folder, "snapshots", stretch)

    def later_end(data: pa.Table) -> pa.Table:
        ends = data["end_tick"].to_numpy().copy()
        ends[-1] += 128 * 700
        index = data.schema.get_field_index("end_tick")
        data = data.set_column(index, "end_tick", pa.array(ends, pa.int32()))
        return data.set_column(
            data.schema.get_field_index("official_end_tick"), "official_end_tick",
            pa.array(ends, pa.int32()),
        )  # fmt: skip

    _edit_table(folder, "rounds", later_end)
    match = read_match(folder)
    assert "is not within 600 s of freeze-time end" in str(match.round_errors[2])


def test_unknown_bomb_events_yaw_and_impossible_damage_are_named(folder: Path) -> None:
    def teleport(data: pa.Table) -> pa.Table:
        events = data["event"].to_pylist()
        events[0] = "teleport"
        return data.set_column(1, "event", pa.array(events, pa.large_string()))

    _edit_table(folder, "bomb", teleport)
    assert any("unknown bomb event 'teleport'" in w for w in read_match(folder).round(1).warnings)

    def spin(data: pa.Table) -> pa.Table:
        yaw = data["yaw"].to_numpy().copy()
        yaw[-1] = np.inf
        return data.set_column(data.schema.get_field_index("yaw"), "yaw", pa.array(yaw))

    _edit_table(folder, "snapshots", spin)
    assert "is not a view angle" in str(read_match(folder).round_errors[2])

    def huge(data: pa.Table) -> pa.Table:
        pre = data["health_pre"].to_numpy().copy()
        pre[0] = 10**9
        return data.set_column(
            data.schema.get_field_index("health_pre"), "health_pre", pa.array(pre)
        )

    _edit_table(folder, "damages", huge)
    assert "HP (a player has 100)" in str(read_match(folder).round_errors[1])


def test_replay_of_a_folder_of_tables_names_its_output_after_its_content(
    folder: Path, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.chdir(tmp_path)  # the default output folder lies under the working folder
    result = CliRunner().invoke(app, ["replay", f"{folder}:1", "--models", "none"])
    assert result.exit_code == 0, result.output
    written = result.output.strip().splitlines()[-1]
    assert written.startswith("replay written to") and "m-" in written and "_r1" in written


def test_a_zip_member_lying_small_about_its_size_is_refused_unread(tmp_path: Path) -> None:
    members = _members(write_awpy2_zip(_sample(), tmp_path / "good.zip"))
    bomb = tmp_path / "bomb.zip"
    with zipfile.ZipFile(bomb, "w", zipfile.ZIP_DEFLATED) as archive:
        for name, data in members.items():
            archive.writestr(name, data + (b"\0" * 50_000_000 if name == "ticks.parquet" else b""))
    raw = bytearray(bomb.read_bytes())
    with zipfile.ZipFile(bomb) as archive:
        info = archive.getinfo("ticks.parquet")
    size_at = info.header_offset + 22  # the local header's uncompressed size
    raw[size_at : size_at + 4] = (1000).to_bytes(4, "little")
    central = raw.rfind(b"PK\x01\x02", 0, raw.find(b"ticks.parquet", info.header_offset + 30))
    raw[central + 24 : central + 28] = (1000).to_bytes(4, "little")
    bomb.write_bytes(bytes(raw))
    with pytest.raises(EstaError, match=r"ticks\.parquet cannot be read"):
        read_match(bomb)


@pytest.mark.parametrize(
    ("table", "column", "value", "said"),
    [
        ("snapshots", "name", pa.array([{"first": "a"}]), "column name holds struct"),
        ("smokes", "x", 1e30, "a smoke bursts at .* off the map"),
        ("blinds", "duration", 1e30, "lasts 1e\\+30 s: left out"),
        ("damages", "dmg_health", 10**9, "deals 1000000000 HP raw"),
    ],
)
def test_values_no_game_has_are_named(
    tmp_path: Path, table: str, column: str, value: object, said: str
) -> None:
    folder = write_awpy3_folder(_with_utility(_sample()), tmp_path / "m")

    def edit(data: pa.Table) -> pa.Table:
        index = data.schema.get_field_index(column)
        if isinstance(value, pa.Array):
            return data.set_column(index, column, pa.repeat(value[0], len(data)))
        values = data[column].to_pylist()
        values[0] = value
        return data.set_column(index, column, pa.array(values, data.schema.field(column).type))

    _edit_table(folder, table, edit)
    try:
        match = read_match(folder)
    except EstaError as error:
        assert re.search(said, str(error))
        return
    told = [str(e) for e in match.round_errors.values()]
    told += [w for r in match.rounds for w in r.warnings]
    assert any(re.search(said, text) for text in told), told


def test_too_many_rounds_and_a_map_name_that_is_a_path_are_refused(folder: Path) -> None:
    rounds = pq.read_table(folder / "rounds.parquet")
    many = pa.concat_tables([rounds] * 101)  # 202 rounds, repeated: refused before reading them
    pq.write_table(many, folder / "rounds.parquet")
    with pytest.raises(EstaError, match="202 rounds"):
        read_match(folder)
    pq.write_table(rounds, folder / "rounds.parquet")
    header = json.loads((folder / "header.json").read_text())
    for name in ("../../etc/de_dust2", "de_" + "x" * 100_000):
        (folder / "header.json").write_text(json.dumps({**header, "map_name": name}))
        with pytest.raises(EstaError, match="names no map") as raised:
            read_match(folder)
        assert len(str(raised.value)) < 500


def test_a_round_without_play_is_refused(folder: Path) -> None:
    def no_play(data: pa.Table) -> pa.Table:
        freeze = data["freeze_end_tick"].to_numpy().copy()
        index = data.schema.get_field_index("end_tick")
        return data.set_column(index, "end_tick", pa.array(freeze, pa.int32()))

    _edit_table(folder, "rounds", no_play)
    with pytest.raises(EstaError, match=r"not in order \(a round has play\)"):
        read_match(folder)


def test_replay_output_does_not_grow_with_the_names(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """Players named with 20,000 characters: the notes that name them are cut when printed."""
    sample = _sample()
    long = [replace(p, name=p.name + "x" * 20_000) for p in sample.rounds[0].players]
    tables = {}
    for table, columns in (
        ("kills", ("attackerName", "victimName")),
        ("damages", ("attackerName", "victimName")),
        ("bomb_events", ("playerName",)),
    ):
        tables[table] = getattr(sample.rounds[0], table).copy()
        for column in columns:
            tables[table][column] = tables[table][column].map(
                lambda n: n + "x" * 20_000 if isinstance(n, str) else n
            )
    first = replace(sample.rounds[0], players=long, **tables)
    folder = write_awpy3_folder(replace(sample, rounds=[first]), tmp_path / "m")
    _edit_table(folder, "snapshots", lambda t: t.drop_columns(["active_weapon"]))  # inferred
    monkeypatch.chdir(tmp_path)
    result = CliRunner().invoke(app, ["replay", f"{folder}:1", "--no-combat", "--no-bomb"])
    assert result.exit_code == 0, result.output[-500:]
    assert "inferred: weapon in hand" in result.output
    assert len(result.output) < 40_000  # each name is 20,000 characters; ten of them


def test_a_tick_table_of_more_rows_than_a_match_holds_is_refused(
    folder: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    from decoy_cli.esta.awpy import reader

    rows = pq.read_metadata(folder / "snapshots.parquet").num_rows
    monkeypatch.setattr(reader, "MAX_TICK_ROWS", rows - 1)
    with pytest.raises(EstaError, match=f"{rows:,} tick rows, more than {rows - 1:,}"):
        read_match(folder)
