"""`decoy snap` and the snap study on generated matches whose players walk the shipped graph.

The fixture match of tests/esta_fixtures.py is rewritten so that every player stands on real
de_dust2 waypoints (walking a shortest path of the shipped graph, one waypoint per frame), with
three planted defects whose effect the tests check: in round 1, t1 floats 5 m above the floor at
frame 2 (unsnappable); in round 2, t2 jumps about 20 m between frames 3 and 4 (too fast for any
weapon); t4 never moves (a plan of STOPs).
"""

from __future__ import annotations

import lzma
import shutil
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from esta_fixtures import make_match, write_match
from typer.testing import CliRunner

from decoy_cli.cli import app
from decoy_cli.csgo import HAMMER_TO_M
from decoy_cli.esta import read_match
from decoy_cli.metrics import METRIC_NAMES
from decoy_cli.replay.pace import MIN_RUN_S
from decoy_cli.replay.plans import PathCache
from decoy_cli.replay.snapping import SnapStatus
from decoy_cli.replay.study import (
    INTERVAL_COLUMNS,
    KEY_COLUMNS,
    combine,
    infeasible_by_place,
    study_files,
    study_round,
)
from decoy_cli.waypoints.build import builtin_graph

DATA = Path(__file__).resolve().parents[1].parent / "shared" / "data"
TSIDE = DATA / "esta_dust2_tside"

runner = CliRunner()
WIDE = {"COLUMNS": "220"}

FLOAT_FRAME = 2
JUMP_FRAME = 4
JUMP_M = 20.0


def _walks(count: int, frames: int) -> list[np.ndarray]:
    """`count` waypoint walks of `frames` nodes (one graph edge per frame) from the T spawn."""
    graph = builtin_graph()
    spawn = graph.region_of("t_spawn")
    walks = []
    for i in range(count):
        start = int(spawn[(37 * i) % len(spawn)])
        dist, _ = graph.path_lengths(start)
        goal = int(np.argmin(np.abs(np.where(np.isfinite(dist), dist, np.inf) - 12.0)))
        path = graph.shortest_path(start, goal)
        walks.append(np.array(path[:frames], dtype=np.int64))
    return walks


def _far_node(node: int) -> int:
    """A waypoint about `JUMP_M` metres of path cost (`edge_cost`) away from `node`."""
    dist, _ = builtin_graph().path_lengths(node)
    return int(np.argmin(np.abs(np.where(np.isfinite(dist), dist, np.inf) - JUMP_M)))


def on_graph_match() -> dict[str, Any]:
    """The fixture match with every player on the shipped graph (see the module docstring)."""
    document = make_match()
    positions = builtin_graph().positions
    names = ["t1", "t2", "t3", "t4", "BOT t5", "ct1", "ct2", "ct3", "ct4"]
    walks = dict(zip(names, _walks(len(names), 6), strict=True))
    walks["t4"] = np.repeat(walks["t4"][:1], 6)
    jump_target = _far_node(int(walks["t2"][JUMP_FRAME - 1]))
    for round_ in document["gameRounds"][:2]:
        for j, frame in enumerate(round_["frames"]):
            for team in ("t", "ct"):
                for player in frame[team]["players"]:
                    node = walks[player["name"]][j]
                    if round_["roundNum"] == 2 and player["name"] == "t2" and j >= JUMP_FRAME:
                        node = jump_target
                    x, y, z = positions[node] / HAMMER_TO_M
                    if round_["roundNum"] == 1 and player["name"] == "t1" and j == FLOAT_FRAME:
                        z += 5.0 / HAMMER_TO_M
                    player.update(x=x, y=y, z=z)
    return document


@pytest.fixture(scope="module")
def match_file(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return write_match(tmp_path_factory.mktemp("snap") / "walk.json.xz", on_graph_match())


def _invoke(*args: str):
    return runner.invoke(app, ["snap", *args], env=WIDE)


def _row(frame, player: str, round_num: int | None = None):
    chosen = frame[frame["player"] == player]
    if round_num is not None:
        chosen = chosen[chosen["round"] == round_num]
    assert len(chosen) == 1
    return chosen.iloc[0]


# --- the library: what the command reports ------------------------------------------------


def test_study_round_finds_the_planted_defects(match_file: Path) -> None:
    match = read_match(match_file)
    one = study_round(match.round(1), builtin_graph(), metrics=True)
    two = study_round(match.round(2), builtin_graph(), metrics=True)
    assert list(one.rows.columns[:4]) == list(KEY_COLUMNS)
    assert _row(one.rows, "t1")["unsnappable"] == 1
    t1 = one.plan.snaps[[p.name for p in one.plan.players].index("t1")]
    assert t1.status[FLOAT_FRAME] == SnapStatus.NO_WAYPOINT
    assert one.rows["unsnappable"].sum() == 1
    # On-graph walks snap exactly and are feasible; t2's jump is the one too-fast interval.
    assert np.nanmax(one.rows["snap_max_m"]) < 1e-6
    assert one.rows["infeasible"].sum() == 0 and one.intervals.empty
    assert two.rows["infeasible"].sum() == 1
    jump = two.intervals.iloc[0]
    assert list(two.intervals.columns) == list(INTERVAL_COLUMNS)
    assert (jump["player"], jump["start_frame"], jump["end_frame"]) == ("t2", 3, 4)
    graph = builtin_graph()
    edges = PathCache(graph).edges(int(jump["from_node"]), int(jump["to_node"]))
    assert edges is not None
    assert jump["length_m"] == pytest.approx(graph.edge_length[edges].sum())
    assert graph.edge_cost[edges].sum() == pytest.approx(JUMP_M, abs=0.8)
    running_s = max(0.5 - graph.edge_air_s[edges].sum(), MIN_RUN_S)  # no headway in the air
    run = graph.edge_run_m[edges].sum()  # the path less what it climbs or falls off ledges
    assert jump["ratio"] == pytest.approx(run / running_s / jump["max_m_s"])
    assert jump["original_m_s"] > jump["max_m_s"]  # the data itself teleports
    assert _row(two.rows, "t4")["path_length_m"] == 0.0


def test_snapped_trajectory_metrics_are_the_snap_errors(match_file: Path) -> None:
    """Clock metrics of S_t = snapped waypoint are exactly the snap errors of the round."""
    round_ = read_match(match_file).round(1)
    study = study_round(round_, builtin_graph(), metrics=True)
    for p, snap in enumerate(study.plan.snaps):
        row = study.rows.iloc[p]
        errors = snap.error_m[snap.status == SnapStatus.SNAPPED]
        assert row["mean_dist"] == pytest.approx(errors.mean(), abs=1e-12)
        assert row["max_dist"] == pytest.approx(errors.max(), abs=1e-12)
        assert row["rmse"] == pytest.approx(np.sqrt(np.mean(errors**2)), abs=1e-12)
    # t1 is not compared at its unsnappable frame, but its other frames are.
    assert study.rows["reason"].isna().all()


def test_study_files_totals_and_failures(match_file: Path, tmp_path: Path) -> None:
    broken = on_graph_match()
    broken["gameRounds"][1]["frames"][2]["t"]["players"][0]["x"] = 1e6
    bad_round = write_match(tmp_path / "bad-round.json", broken)
    corrupt = tmp_path / "corrupt.json.xz"
    corrupt.write_bytes(lzma.compress(b'{"gameRounds": []}')[:-9])
    reported: list[tuple[float, int]] = []
    study = study_files(
        [match_file, bad_round, corrupt],
        builtin_graph(),
        metrics=True,
        on_progress=lambda files, rounds: reported.append((round(files, 3), rounds)),
    )
    assert reported == [
        *[(0.333, 1), (0.667, 2), (1.0, 3), (1.0, 3)],  # walk.json.xz: 3 rounds
        *[(1.5, 4), (2.0, 5), (2.0, 5)],  # bad-round.json: round 2 failed in the reader
        (3.0, 5),  # corrupt.json.xz
    ]
    assert [(Path(f.file).name, f.round_num) for f in study.failures] == [
        ("bad-round.json", 2),
        ("corrupt.json.xz", None),
    ]
    assert "off the map" in study.failures[0].message
    totals = study.totals
    assert totals.rounds == 5 and totals.player_rounds == 3 * 9  # round 3 has no frames
    assert totals.unsnappable == 2 and totals.infeasible == 1
    assert totals.snap_median_m < 1e-6
    assert totals.within == pytest.approx(1 - 2 / totals.frames_with_position)
    assert study.metrics is not None and study.metrics.n_evaluated["T"] == 3 * 5
    assert study.worst(3)["player"].iloc[0] == "t2"
    places = infeasible_by_place(study.intervals)
    assert places["intervals"].tolist() == [1] and places["share"].tolist() == [1.0]
    empty = combine([], metrics=True)
    assert empty.totals.player_rounds == 0 and empty.metrics is not None
    # asked for metrics of nothing: every group is there, with nothing evaluated in it
    assert empty.metrics.n_evaluated == {"T": 0, "CT": 0, "all": 0}
    assert combine([], metrics=False).metrics is None


# --- decoy snap FILE:ROUND ----------------------------------------------------------------


def test_round_table(match_file: Path) -> None:
    result = _invoke(f"{match_file}:2")
    assert result.exit_code == 0, result.output
    assert "fixture-0001 round 2: 6 frames" in result.stdout
    for name in ("t1", "t2", "BOT t5", "ct4"):
        assert name in result.stdout
    totals = next(line for line in result.stdout.splitlines() if line.startswith("│ all"))
    assert "1 (2.2%)" in totals  # one too-fast interval of 9 players × 5 intervals
    assert "worst intervals" in result.stdout and "3→4" in result.stdout


def test_round_actions_plot_and_csv(match_file: Path, tmp_path: Path) -> None:
    png, csv = tmp_path / "round.png", tmp_path / "rows.csv"
    result = _invoke(
        f"{match_file}:2",
        "--actions",
        "4",
        "--player",
        "t4",
        "--player",
        "ct1",
        "--plot",
        str(png),
        "--frames",
        "1:4",
        "--csv",
        str(csv),
    )
    assert result.exit_code == 0, result.output
    t4 = next(line for line in result.stdout.splitlines() if line.startswith("t4 "))
    assert "STOP×4 2.00s" in t4  # 4 intervals of 0.5 s standing still, none collapsed
    ct1 = next(line for line in result.stdout.splitlines() if line.startswith("ct1 "))
    assert any(f" {d}" in ct1.split(":", 1)[1] for d in ("N", "E", "S", "W"))
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    rows = csv.read_text().splitlines()
    assert rows[0].startswith("match,round,player,side,frames_alive") and len(rows) == 10


def test_round_metrics(match_file: Path) -> None:
    result = _invoke(f"{match_file}:1", "--metrics")
    assert result.exit_code == 0, result.output
    for name in METRIC_NAMES:
        assert f" {name} " in result.stdout


@pytest.mark.parametrize(
    ("suffix", "extra", "expected"),
    [
        (":9", [], "error: {file}: no round 9 (rounds 1-3)"),
        (":1", ["--player", "nobody"], "error: round 1 has no player 'nobody' (players: "),
    ],
)
def test_round_errors_are_one_line(
    match_file: Path, suffix: str, extra: list[str], expected: str
) -> None:
    result = _invoke(f"{match_file}{suffix}", *extra)
    assert result.exit_code == 1
    assert result.stderr.startswith(expected.format(file=match_file))
    assert result.stderr.count("\n") == 1 and "Traceback" not in result.output


def test_corrupt_file_is_one_error_line(tmp_path: Path) -> None:
    corrupt = tmp_path / "corrupt.json.xz"
    corrupt.write_bytes(lzma.compress(b'{"gameRounds": []}')[:-9])
    for target in (f"{corrupt}:1", str(corrupt)):
        result = _invoke(target)
        assert result.exit_code == 1
        assert result.stderr.startswith(f"error: {corrupt}: corrupt or truncated xz data")
        assert result.stderr.count("\n") == 1 and result.stdout == ""


def test_other_map_is_refused(tmp_path: Path) -> None:
    document = on_graph_match()
    document["mapName"] = "de_inferno"
    path = write_match(tmp_path / "inferno.json", document)
    result = _invoke(f"{path}:1")
    assert result.exit_code == 1
    assert result.stderr == (
        f"error: {path}: a de_inferno match cannot be snapped to the de_dust2 waypoint graph\n"
    )


def test_round_only_options_need_a_round(match_file: Path, tmp_path: Path) -> None:
    result = _invoke(str(match_file), "--plot", str(tmp_path / "x.png"))
    assert result.exit_code == 2 and "--plot needs one round" in result.output
    result = _invoke(f"{match_file}:1", "--frames", "3:9")
    assert result.exit_code == 2 and "--frames wants FIRST:LAST" in result.output


# --- decoy snap FILE / FOLDER ---------------------------------------------------------------


def test_file_aggregate(match_file: Path) -> None:
    result = _invoke(str(match_file), "--metrics")
    assert result.exit_code == 0, result.output
    out = result.stdout
    assert "│ rounds snapped" in out and "│ player-rounds " in out
    line = next(x for x in out.splitlines() if "needing more than max speed" in x)
    assert line.rstrip(" │").endswith("1 (1.4%)")  # 1 of 24 + 45 intervals (rounds 1, 2)
    assert "where the intervals needing more than max speed are" in out
    for name in METRIC_NAMES:
        assert f" {name} " in out
    for group in ("T mean", "CT mean", "all p90"):
        assert group in out
    assert "player-rounds evaluated: T: 10 of 10, CT: 8 of 8, all: 18 of 18" in out


def test_folder_goes_on_after_failures(match_file: Path, tmp_path: Path) -> None:
    folder = tmp_path / "matches"
    folder.mkdir()
    shutil.copy(match_file, folder / "a.json.xz")
    broken = on_graph_match()
    broken["gameRounds"][0]["frames"][1]["t"]["players"][2]["activeWeapon"] = "Railgun"
    write_match(folder / "b.json", broken)
    (folder / "c.json").write_text("{not json")
    csv = tmp_path / "rows.csv"
    result = _invoke(str(folder), "--csv", str(csv))
    assert result.exit_code == 1
    assert "unknown weapon 'Railgun'" in result.stdout and "c.json: invalid JSON" in result.stdout
    assert result.stderr == "error: 1 rounds and 1 files could not be snapped (5 rounds were)\n"
    rows = csv.read_text().splitlines()
    assert len(rows) == 1 + 3 * 9  # a.json.xz rounds 1-2 and b.json round 2


# --- the real T-side data -----------------------------------------------------------------


def test_real_match_file() -> None:
    if not TSIDE.is_dir():
        pytest.skip(f"real ESTA data not found at {TSIDE} (../shared/data next to the repo)")
    path = sorted(TSIDE.glob("*.json.xz"))[0]
    result = _invoke(str(path), "--metrics", "--worst", "3")
    assert result.exit_code == 0, result.output
    assert "snap error median (m)" in result.stdout
    study = study_files([path], builtin_graph(), metrics=True)
    totals = study.totals
    assert totals.rounds == len(read_match(path).rounds) and not study.failures
    # The shipped graph covers real T positions: most snap within 0.5 m, almost none fail.
    assert 0.15 < totals.snap_median_m < 0.45 and totals.within > 0.8
    assert totals.unsnappable < 0.02 * totals.frames_with_position
    table = study.metrics.table.set_index(["group", "metric"])  # type: ignore[union-attr]
    assert table.loc[("T", "mean_dist"), "mean"] == pytest.approx(study.rows["mean_dist"].mean())


def test_snap_tells_frames_in_the_air_apart_as_the_replay_does(tmp_path: Path) -> None:
    """With the world, a frame 1 m above the floor (a jump's apex) is in the air: not snapped
    and not unsnappable. The command opens the world as the replay does and counts it; without
    the world the library cannot tell (the frame snaps, 1 m off)."""
    from decoy_cli.sim.setup import RoundSetup

    document = on_graph_match()
    t1 = next(
        p
        for p in document["gameRounds"][0]["frames"][FLOAT_FRAME]["t"]["players"]
        if p["name"] == "t1"
    )
    t1["z"] -= 4.0 / HAMMER_TO_M  # from 5 m above its waypoint to 1 m
    path = write_match(tmp_path / "jump.json.xz", document)
    graph = builtin_graph()
    round_ = read_match(path).round(1)
    with RoundSetup(graph=graph).open_physics() as physics:
        one = study_round(round_, graph, physics=physics)
    snap = one.plan.snaps[[p.name for p in one.plan.players].index("t1")]
    assert snap.status[FLOAT_FRAME] == SnapStatus.AIRBORNE
    assert _row(one.rows, "t1")["airborne"] == 1 and one.totals.airborne == 1
    assert one.rows["unsnappable"].sum() == 0
    blind = study_round(round_, graph)
    assert _row(blind.rows, "t1")["airborne"] == 0 and blind.totals.airborne == 0
    result = _invoke(str(path))
    assert result.exit_code == 0, result.output
    line = next(x for x in result.stdout.splitlines() if "frames in the air" in x)
    assert line.rstrip(" │").endswith(" 1")
