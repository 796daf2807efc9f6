"""`decoy replay FILE:ROUND` on a generated match whose players walk the shipped graph, its
error lines, and one real round.

The fixture match of tests/esta_fixtures.py is rewritten so that every player of rounds 1 and 2
walks north along one straight run of de_dust2 waypoints in the T spawn, one waypoint per frame,
each four waypoints (2.8 m) behind the next. Round 1 keeps the fixture's quirks: t3 dies at
frame 3 and ct4 is missing from frame 2. Round 3 has no frames.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd
import pytest
from esta_fixtures import MATCH_ID, ROUND1_TICKS, make_match, write_match
from typer.testing import CliRunner

from decoy_cli.cli import app
from decoy_cli.csgo import HAMMER_TO_M
from decoy_cli.esta import read_match
from decoy_cli.metrics import METRIC_NAMES
from decoy_cli.waypoints.build import builtin_graph

DATA = Path(__file__).resolve().parents[1].parent / "shared" / "data"
TSIDE = DATA / "esta_dust2_tside"

runner = CliRunner()
WIDE = {"COLUMNS": "220"}

RUN_START = (5.458, -19.007, 0.008)
"""A T-spawn waypoint with a straight run of 40 walk edges north."""
NAMES = ["t1", "t2", "t3", "t4", "BOT t5", "ct1", "ct2", "ct3", "ct4"]
SPACING = 4  # waypoints between neighbours on the run

REPLAY_FILES = ("replay.csv", "events.csv", "players.csv", "summary.json", "paths.png")
PNG_MAGIC = b"\x89PNG\r\n\x1a\n"
BOMB_KINDS = {"plant_begin", "plant", "plant_abort", "bomb_drop", "bomb_pickup", "explode"}


def _run() -> list[int]:
    graph = builtin_graph()
    index, distance = graph.nearest(np.array([RUN_START]))
    assert distance[0] < 0.01
    run = [int(index[0])]
    while len(run) < SPACING * len(NAMES) + 6:
        run.append(int(graph.edge_target[graph.out_edges[run[-1], 0]]))
    return run


def on_graph_match() -> dict[str, Any]:
    """The fixture match with every player on the shipped graph (see the module docstring)."""
    document = make_match()
    positions = builtin_graph().positions
    run = _run()
    for round_ in document["gameRounds"][:2]:
        for j, frame in enumerate(round_["frames"]):
            for team in ("t", "ct"):
                for player in frame[team]["players"]:
                    node = run[SPACING * NAMES.index(player["name"]) + j]
                    x, y, z = positions[node] / HAMMER_TO_M
                    player.update(x=x, y=y, z=z)
    return document


@pytest.fixture(scope="module")
def match_file(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return write_match(tmp_path_factory.mktemp("replay") / "walk.json.xz", on_graph_match())


def _invoke(*args: str):
    return runner.invoke(app, ["replay", *args], env=WIDE)


def test_replay_writes_its_files_and_prints_the_tables(match_file: Path, tmp_path: Path) -> None:
    out = tmp_path / "out"
    result = _invoke(
        f"{match_file}:1", "--mover", "kinematic", "--no-combat", "--out", str(out), "--gif"
    )
    assert result.exit_code == 0, result.output
    for name in (*REPLAY_FILES, "round.gif"):
        assert (out / name).stat().st_size > 0, name
    assert (out / "paths.png").read_bytes().startswith(PNG_MAGIC)
    assert (out / "round.gif").read_bytes()[:6] in (b"GIF87a", b"GIF89a")

    stdout = result.stdout
    assert f"round 1 of {MATCH_ID}: {len(ROUND1_TICKS)} frames (2 frames/s) replayed" in stdout
    assert "kinematic mover, combat off, bomb on" in stdout
    for title in ("outcome", "clock protocol (metres)", "paper protocol (metres)"):
        assert title in stdout
    for name in (*METRIC_NAMES, *NAMES):
        assert f" {name} " in stdout, name
    assert "end of the data" in stdout  # nobody won: the data ends first
    assert f"replay written to {out}" in stdout

    frames, players = len(ROUND1_TICKS), len(NAMES)
    table = pd.read_csv(out / "replay.csv", keep_default_na=False)
    assert len(table) == frames * players
    seconds = (np.array(ROUND1_TICKS) - 990) / 128
    assert table["tick"].tolist() == np.repeat(np.round(seconds * 60), players).tolist()
    t3 = table[table["player"] == "t3"]
    assert t3["alive"].tolist() == [True, True, True, False]  # dead from frame 3, as in the data
    assert t3["alive_original"].tolist() == [True, True, True, False]

    per_player = pd.read_csv(out / "players.csv", keep_default_na=False).set_index("player")
    assert per_player.loc["t3", "death"] == "scripted"
    assert per_player["died_replay"].tolist() == [name == "t3" for name in per_player.index]
    events = pd.read_csv(out / "events.csv")
    assert events[["kind", "agent"]].values.tolist() == [["death", "t3"]]

    summary = json.loads((out / "summary.json").read_text())
    assert summary["options"] == {
        "combat": False,
        "bomb": True,
        "mover": "kinematic",
        "seed": 0,
        "implausible": "fail",
        "deaths": "data (no shooting)",
        "missing_fields": "infer",
    }
    # the file's winner is T by elimination, yet its frames keep CTs alive: named, replayed
    assert summary["warnings"] == []
    assert summary["contradictions"] == [
        "the round ends TerroristsWin, yet ct1, ct2, ct3, ct4 of the CT side are alive at its end"
    ]
    # two players hold no weapon in any frame (round 1: a pistol round); the others have theirs
    assert summary["inferred"] == [
        "weapon in hand (t2): Glock-18: a pistol round",
        "weapon in hand (ct1): USP-S: a pistol round",
    ]
    assert summary["frames"] == frames and summary["round_num"] == 1
    assert summary["frame_rate"] == "2 frames/s"  # the data's: 64 ticks apart at 128 tick
    assert summary["outcome_original"] == {"winner": "T", "reason": "TerroristsWin"}
    assert summary["outcome_replay"] == {"winner": None, "reason": None}


def test_physics_mover_without_the_bomb(match_file: Path, tmp_path: Path) -> None:
    out = tmp_path / "out"
    args = (f"{match_file}:2", "--mover", "physics", "--no-bomb", "--models", "none")
    result = _invoke(*args, "--out", str(out))
    assert result.exit_code == 0, result.output
    assert "physics mover, combat off, bomb off" in result.stdout
    assert "--models none" in result.stdout  # combat was asked for: the user is told
    assert not (out / "round.gif").exists()
    summary = json.loads((out / "summary.json").read_text())
    assert summary["options"]["bomb"] is False and summary["options"]["mover"] == "physics"
    events = pd.read_csv(out / "events.csv")
    assert not set(events["kind"]) & BOMB_KINDS


@pytest.mark.parametrize(
    ("target", "extra", "expected"),
    [
        ("{missing}:1", [], "error: {missing}: no such file"),
        ("{file}:9", [], "error: {file}: no round 9 (rounds 1-3)"),
        ("{file}:3", [], "error: round 3 has no frames (events only): nothing to replay"),
        ("{file}", [], "error: {file}: not a round address (expected FILE:ROUND"),
        ("{file}:1", ["--out", "{blocker}"], "error: cannot create {blocker}: "),
    ],
    ids=["missing-file", "missing-round", "no-frames", "no-round", "bad-out"],
)
def test_bad_input_is_one_error_line(
    match_file: Path, tmp_path: Path, target: str, extra: list[str], expected: str
) -> None:
    blocker = tmp_path / "a-file"
    blocker.write_text("not a folder")
    names = {"file": match_file, "missing": tmp_path / "nope.json.xz", "blocker": blocker}
    args = [target.format(**names), *(a.format(**names) for a in extra)]
    result = _invoke(*args, "--no-combat")
    assert result.exit_code == 1
    assert result.stderr.startswith(expected.format(**names))
    assert result.stderr.count("\n") == 1 and "Traceback" not in result.output


def test_an_option_value_not_among_its_choices_is_one_usage_line(match_file: Path) -> None:
    result = _invoke(f"{match_file}:1", "--mover", "nonsense", "--no-combat")
    assert result.exit_code == 2 and result.stderr.count("\n") == 1
    assert result.stderr.startswith("error: Invalid value for '--mover': ")
    assert "'nonsense' is not one of 'kinematic', 'physics'" in result.stderr
    assert result.stderr.rstrip().endswith("replay --help)")


@pytest.mark.parametrize(
    ("file_map", "extra", "message"),
    [
        ("de_cache", [], "a de_cache round, a map decoy has no world for"),
        ("de_inferno", ["--map", "dust2"], "a de_inferno round, not de_dust2 (--map)"),
    ],
)
def test_a_round_of_a_map_without_a_world_or_not_the_asked_one_is_refused(
    tmp_path: Path, file_map: str, extra: list[str], message: str
) -> None:
    document = on_graph_match()
    document["mapName"] = file_map
    path = write_match(tmp_path / "other.json", document)
    result = _invoke(f"{path}:1", *extra, "--out", str(tmp_path / "out"))
    assert result.exit_code == 1
    assert result.stderr == f"error: {path}:1: {message}\n"
    assert not (tmp_path / "out").exists()


def test_an_unknown_map_option_names_the_known_maps(tmp_path: Path) -> None:
    path = write_match(tmp_path / "m.json", on_graph_match())
    result = _invoke(f"{path}:1", "--map", "cache", "--out", str(tmp_path / "out"))
    assert result.exit_code == 1
    assert result.stderr.startswith("error: unknown map 'cache'; this decoy knows: ancient, dust2")


def test_a_real_round(tmp_path: Path) -> None:
    files = sorted(TSIDE.glob("*.json.xz")) if TSIDE.is_dir() else []
    if not files:
        pytest.skip(f"real ESTA data not found at {TSIDE}")
    match = read_match(files[0])
    round_ = match.rounds[0]
    out = tmp_path / "real"
    result = _invoke(
        f"{files[0]}:{round_.round_num}", "--mover", "kinematic", "--no-combat", "--out", str(out)
    )
    assert result.exit_code == 0, result.output
    for name in REPLAY_FILES:
        assert (out / name).stat().st_size > 0, name
    table = pd.read_csv(out / "replay.csv")
    assert len(table) == round_.num_frames * round_.num_players
    assert np.array_equal(
        table["tick"].to_numpy(), np.repeat(np.round(round_.frame_seconds * 60), 5)
    )
    per_player = pd.read_csv(out / "players.csv", keep_default_na=False)
    assert len(per_player) == round_.num_players == 5
    # Movement only: every death in the data is scripted at its time, and survivors survive.
    assert per_player["died_replay"].tolist() == per_player["died_original"].tolist()
    # The replay stays near the players: within a few metres on average.
    assert per_player["mean_dist"].astype(float).max() < 5.0
    summary = json.loads((out / "summary.json").read_text())
    assert summary["frames"] == round_.num_frames and summary["match_id"] == match.match_id


SAMPLE = (
    Path(__file__).resolve().parents[1] / "examples" / "sample" / "synthetic-dust2-seed0.json.xz"
)


def test_replay_shoots_with_the_default_models_and_decides_the_round(tmp_path: Path) -> None:
    """By default the replay shoots with the shipped DIP and the game's damage rules; a round the
    data leaves open is played on until the rules end it, and the summary says so."""
    out = tmp_path / "out"
    result = _invoke(f"{SAMPLE}:7", "--out", str(out))
    assert result.exit_code == 0, result.output
    assert "combat on" in result.stdout
    summary = json.loads((out / "summary.json").read_text())
    assert summary["damage_models"] == "rules"
    assert summary["outcome_replay"]["winner"] in ("T", "CT")
    events = pd.read_csv(out / "events.csv")
    assert "damage" in set(events["kind"])
    # played on: the seconds from the data's last frame (the last recorded tick) to the round end
    last_frame_tick = int(pd.read_csv(out / "replay.csv")["tick"].max())
    (end_tick,) = events.loc[events["kind"] == "round_end", "tick"].tolist()
    assert end_tick > last_frame_tick  # this round is left open by its data
    assert summary["played_out_s"] == pytest.approx((end_tick - last_frame_tick) / 60, abs=1e-3)
    assert f"({summary['played_out_s']:.1f} s after the data)" in result.stdout


def test_a_replay_that_cannot_finish_writing_leaves_the_previous_one_whole(
    match_file: Path, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    out = tmp_path / "out"
    args = (f"{match_file}:1", "--no-combat", "--out", str(out))
    assert _invoke(*args).exit_code == 0
    before = {path.name: path.read_bytes() for path in out.iterdir()}

    def disk_full(*args: object, **kwargs: object) -> None:
        raise OSError(28, "No space left on device")  # after the CSV files and summary.json

    monkeypatch.setattr("decoy_cli.replay.single.plot_paths", disk_full)
    result = _invoke(*args, "--seed", "7")
    assert result.exit_code == 1 and "Traceback" not in result.output
    assert "No space left on device" in result.output
    assert {path.name: path.read_bytes() for path in out.iterdir()} == before  # nothing mixed
