"""Rounds the replay cannot play on one clock are one `error:` line, never a traceback; and an
unexpected exception anywhere is reported in one line as a bug (issue 17's error boundary)."""

from __future__ import annotations

import copy
import json
from pathlib import Path
from typing import Any

import pytest
from esta_fixtures import make_match, write_match
from typer.testing import CliRunner

from decoy_cli.cli import app

runner = CliRunner()
WIDE = {"COLUMNS": "220"}


def _replay(file: Path, round_num: int, tmp_path: Path, *args: str):
    address = f"{file}:{round_num}"
    return runner.invoke(app, ["replay", address, "--out", str(tmp_path / "out"), *args], env=WIDE)


def _frames(document: dict[str, Any], round_index: int) -> list[dict[str, Any]]:
    return document["gameRounds"][round_index]["frames"]


def _one_error_line(result) -> str:
    assert result.exit_code == 1, result.output
    assert "Traceback" not in result.output
    assert result.stderr.count("\n") == 1 and result.stderr.startswith("error: ")
    return result.stderr.strip()


def test_a_round_with_no_player_in_any_frame(tmp_path: Path) -> None:
    document = make_match()
    for frame in _frames(document, 0):
        frame["t"]["players"] = []
        frame["ct"]["players"] = []
    file = write_match(tmp_path / "empty.json", document)
    line = _one_error_line(_replay(file, 1, tmp_path, "--models", "none"))
    assert line == f"error: {file}: round 1: no player in any frame: nothing to replay"


def test_frames_on_one_tick(tmp_path: Path) -> None:
    document = make_match()
    frames = _frames(document, 0)
    for frame in frames:
        frame["tick"] = frames[0]["tick"]
        frame["seconds"] = frames[0]["seconds"]
    file = write_match(tmp_path / "same.json", document)
    line = _one_error_line(_replay(file, 1, tmp_path, "--models", "none"))
    assert line.startswith(f"error: {file}: round 1: frame 1 (")
    assert line.endswith("frames must be at distinct times")


def test_the_bomb_carried_by_a_player_listed_as_ct(tmp_path: Path) -> None:
    document = make_match()
    for frame in _frames(document, 0):
        for player in frame["t"]["players"]:
            player["hasBomb"] = False
        for player in frame["ct"]["players"]:
            player["hasBomb"] = player["name"] == "ct1"
    file = write_match(tmp_path / "swapped.json", document)
    line = _one_error_line(_replay(file, 1, tmp_path, "--models", "none"))
    assert line == (
        f"error: {file}: round 1: ct1 on the CT side holds the bomb at frame 0: only a T can "
        "carry it"
    )
    assert _replay(file, 1, tmp_path, "--models", "none", "--no-bomb").exit_code == 0


@pytest.mark.parametrize("command", [["info"], ["evaluate", "--out", "{tmp}/out"]])
def test_a_path_the_system_refuses_is_one_error_line(tmp_path: Path, command: list[str]) -> None:
    too_long = tmp_path / ("a" * 300 + ".json.xz")
    args = [part.replace("{tmp}", str(tmp_path)) for part in command]
    result = runner.invoke(app, [*args[:1], str(too_long), *args[1:]], env=WIDE)
    assert _one_error_line(result).endswith("File name too long")


def test_an_unexpected_exception_is_reported_as_a_bug(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    file = write_match(tmp_path / "m.json")

    def broken(*args: object, **kwargs: object) -> None:
        raise ZeroDivisionError("division by zero")

    monkeypatch.setattr("decoy_cli.replay.single.replay_round", broken)
    result = _replay(file, 1, tmp_path, "--models", "none")
    assert result.exit_code == 2 and "Traceback" not in result.output
    assert result.stderr.startswith(
        "error: internal error (a bug in decoy, please report it): "
        "ZeroDivisionError: division by zero at test_replay_hostile.py:"
    )
    assert result.stderr.strip().endswith("rerun with --debug for the traceback")


def test_the_data_never_chooses_the_output_path(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """matchIDs that climb out of the folder, hold a NUL, or share their first characters:
    every default replay folder lies inside decoy-out/replay, one per input file."""
    work = tmp_path / "work"
    work.mkdir()
    monkeypatch.chdir(work)
    ids = ["../../escaped", "bad\x00id", "synthetic-dust2-seed0", "synthetic-dust2-seed1"]
    folders = []
    for k, match_id in enumerate(ids):
        document = make_match()
        document["matchID"] = match_id
        file = write_match(tmp_path / f"m{k}.json", document)
        result = runner.invoke(app, ["replay", f"{file}:1", "--models", "none"], env=WIDE)
        if result.exit_code == 1:  # the reader may refuse such a matchID: a clean error then
            _one_error_line(result)
            continue
        assert result.exit_code == 0, result.output
        folders.append(result.stdout.strip().splitlines()[-1].removeprefix("replay written to "))
    replay_root = (work / "decoy-out" / "replay").resolve()
    resolved = [(work / folder).resolve() for folder in folders]
    assert len(resolved) >= 3
    assert all(folder.parent == replay_root for folder in resolved), folders
    assert len(set(resolved)) == len(resolved)
    assert not list(tmp_path.rglob("escaped"))


@pytest.mark.parametrize(
    ("change", "expected"),
    [
        ("scale", "frame time 60000 s disagrees with its tick"),
        ("back", "s is before the previous frame's"),
    ],
)
def test_a_broken_frame_clock_is_the_round_failure(
    tmp_path: Path, change: str, expected: str
) -> None:
    """Frame times 1000 times too large (a replay of hours) or running backwards: the reader
    refuses the round, naming the frame, before anything is simulated."""
    document = make_match()
    frames = _frames(document, 0)
    if change == "scale":
        for k, frame in enumerate(frames):
            frame["seconds"] = 1000.0 * (60.0 + k)
    else:
        frames[2]["seconds"], frames[1]["seconds"] = frames[1]["seconds"], frames[2]["seconds"]
    file = write_match(tmp_path / "clock.json", document)
    line = _one_error_line(_replay(file, 1, tmp_path, "--models", "none"))
    assert line.startswith(f"error: {file}: round 1: frame ") and expected in line


def test_a_round_over_its_time_limit_is_a_timeout_failure(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """A hung round cannot hang the batch: the job interrupts it at the task's limit."""
    import time

    from decoy_cli.evaluate import job
    from decoy_cli.evaluate.job import RoundTask, evaluate_round
    from decoy_cli.evaluate.runner import make_settings

    def hang(task: RoundTask) -> None:
        time.sleep(30)

    monkeypatch.setattr(job, "_evaluate", hang)
    settings = make_settings(
        map_name="dust2", combat=False, bomb=False, models="none", mover="kinematic", seed=0
    )
    task = RoundTask("m.json", "0" * 64, 3, "key", settings, timeout_s=0.2)
    started = time.perf_counter()
    failure = evaluate_round(task)
    assert time.perf_counter() - started < 5
    assert (failure.file, failure.round_num, failure.kind) == ("m.json", 3, "timeout")
    assert failure.message == "the round took longer than its time limit of 0.2 s"


def _first_frame_player(document: dict[str, Any], name: str) -> dict[str, Any]:
    frame = _frames(document, 0)[1]
    return next(p for p in frame["t"]["players"] + frame["ct"]["players"] if p["name"] == name)


IMPLAUSIBLE = [
    ("hp", "frame 1 (tick 1064): ct1 has HP 250 (at most 100)"),
    ("teleport", "frame 1 (tick 1064): ct1 moved "),
    ("crowd", "frame 0 (tick 1000): 6 CT players (a side has at most 5)"),
    (
        "revival",
        "frame 2 (tick 1128): ct1 is alive again after being dead in frame 1 (nothing revives a "
        "player within a round)",
    ),
    (
        "hp_rise",
        "frame 2 (tick 1128): ct1's HP rose to 100 from 40 in frame 1 (nothing gives back health "
        "within a round)",
    ),
    (
        "both_sides",
        "frame 2 (tick 1128): ct2 plays for T after playing for CT since frame 0 (a player keeps "
        "one side within a round)",
    ),
    (
        "clock_back",
        "starts at tick 900, before round 0 has ended (tick 5400): the file's clock runs backwards",
    ),
    ("no_x", "no player has a position (x, y and z) in any frame"),
    ("off_map", "frame 0: ct1 at "),
]


def _make_implausible(document: dict[str, Any], case: str) -> None:
    """Break round 1 of `document` in the way `case` names."""
    if case == "hp":
        _first_frame_player(document, "ct1")["hp"] = 250
    elif case == "teleport":
        _first_frame_player(document, "ct1")["x"] += 95 / 0.01905  # 95 m in half a second
    elif case == "crowd":
        for frame in _frames(document, 0):
            extra = copy.deepcopy(frame["ct"]["players"][0])
            extra["name"], extra["steamID"] = "ct9", 76561198000000019
            frame["ct"]["players"].append(extra)
            extra2 = copy.deepcopy(extra)
            extra2["name"], extra2["steamID"] = "ct8", 76561198000000018
            frame["ct"]["players"].append(extra2)
    elif case == "revival":
        _first_frame_player(document, "ct1").update(hp=0, isAlive=False)
    elif case == "hp_rise":
        _first_frame_player(document, "ct1")["hp"] = 40
    elif case == "both_sides":
        for frame in _frames(document, 0)[2:]:
            ct2 = next(p for p in frame["ct"]["players"] if p["name"] == "ct2")
            frame["ct"]["players"].remove(ct2)
            frame["t"]["players"] = [p for p in frame["t"]["players"] if p["name"] != "t1"]
            frame["t"]["players"].append(ct2)
    elif case == "clock_back":
        document["gameRounds"][1]["roundNum"] = 0
    elif case == "no_x":
        for frame in _frames(document, 0):
            for player in frame["t"]["players"] + frame["ct"]["players"]:
                player["x"] = None
    else:
        for frame in _frames(document, 0):
            for player in frame["ct"]["players"]:
                if player["name"] == "ct1":
                    player["z"] += 57 / 0.01905


@pytest.mark.parametrize(("case", "expected"), IMPLAUSIBLE)
def test_implausible_data_is_the_round_failure(tmp_path: Path, case: str, expected: str) -> None:
    """Silent garbage no more: impossible data fails the round by name."""
    document = make_match()
    _make_implausible(document, case)
    file = write_match(tmp_path / f"{case}.json", document)
    line = _one_error_line(_replay(file, 1, tmp_path, "--models", "none"))
    assert expected in line, line


@pytest.mark.parametrize(("case", "expected"), IMPLAUSIBLE[:-2] + IMPLAUSIBLE[-1:])
def test_implausible_data_replayed_with_a_warning(tmp_path: Path, case: str, expected: str) -> None:
    """--implausible warn replays such a round and says what is wrong with it, in the terminal
    and in summary.json; a round with no position at all still fails (nothing to replay)."""
    document = make_match()
    _make_implausible(document, case)
    file = write_match(tmp_path / f"{case}.json", document)
    result = _replay(file, 1, tmp_path, "--models", "none", "--implausible", "warn")
    assert result.exit_code == 0, result.output
    assert f"warning: implausible data replayed anyway: {expected}" in result.stdout
    summary = json.loads((tmp_path / "out" / "summary.json").read_text())
    assert summary["options"]["implausible"] == "warn"
    assert any(expected in warning for warning in summary["warnings"]), summary["warnings"]


def test_a_round_without_positions_fails_under_either_policy(tmp_path: Path) -> None:
    document = make_match()
    _make_implausible(document, "no_x")
    file = write_match(tmp_path / "no_x.json", document)
    result = _replay(file, 1, tmp_path, "--models", "none", "--implausible", "warn")
    assert _one_error_line(result).endswith("no player has a position (x, y and z) in any frame")


def test_an_unknown_policy_is_one_error_line(tmp_path: Path) -> None:
    file = write_match(tmp_path / "m.json", make_match())
    result = _replay(file, 1, tmp_path, "--implausible", "ignore")
    assert result.exit_code == 2, result.output  # a usage error, as for every choice
    assert "Traceback" not in result.output and result.stderr.count("\n") == 1
    assert result.stderr.startswith("error: Invalid value for '--implausible'")
    assert "'ignore' is not one of 'fail', 'warn'" in result.stderr
