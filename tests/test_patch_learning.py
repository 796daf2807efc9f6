"""Floor patches learned from where players stand (decoy_cli/world/patch_learning.py) and
`decoy build-waypoints --learn-patches`: hand-made positions on hand-made worlds, the ESTA
fixture for the standing rule and bad input, and the real T-side data when it is present."""

from __future__ import annotations

import csv
import json
import re
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest
from esta_fixtures import T_PLAYERS, make_match, write_match
from typer.testing import CliRunner
from worlds import floor, make_world

from decoy_cli.cli import app
from decoy_cli.csgo import HAMMER_TO_M
from decoy_cli.errors import WorldError
from decoy_cli.waypoints.build import graph_world
from decoy_cli.waypoints.graph import WaypointGraph
from decoy_cli.world.nav_data import NavMesh, read_patches
from decoy_cli.world.navmesh import load_navmesh
from decoy_cli.world.patch_boxes import SLAB_U
from decoy_cli.world.patch_learning import (
    PatchBox,
    StandingPositions,
    _match_tracks,
    learn_patches,
    patches_csv,
    read_positions,
)
from decoy_cli.world.physics import PhysicsWorld

DATA = Path(__file__).resolve().parents[1].parent / "shared" / "data"
TSIDE = DATA / "esta_dust2_tside"

runner = CliRunner()

SIZE_U = 2000.0
"""Side of the hand-made flat world (Hammer units)."""


def flat_nav() -> NavMesh:
    """One nav area over the whole hand-made floor."""
    one = np.array
    return NavMesh(
        area_id=one([1]),
        place=one(["Floor"]),
        x_min=one([0.0]),
        y_min=one([0.0]),
        x_max=one([SIZE_U]),
        y_max=one([SIZE_U]),
        z_at_min=one([0.0]),
        z_at_max=one([0.0]),
        connections=np.zeros((0, 2), dtype=np.int64),
        radar={},
        regions={},
    )


def flat_world():
    size = SIZE_U * HAMMER_TO_M
    return make_world([floor(0.0, 0.0, size, size)], "flat", (1.0, 1.0, 0.0))


def on_a_surface(
    matches: int, top_u: float, x0: float = 500.0, y0: float = 500.0, side: float = 96.0
) -> StandingPositions:
    """Positions spread over a square surface at height `top_u`, in each of `matches` matches."""
    rng = np.random.default_rng(7)
    per = 40
    xy = rng.uniform([x0, y0], [x0 + side, y0 + side], size=(matches * per, 2))
    return StandingPositions(
        position=np.column_stack([xy, np.full(len(xy), top_u)]),
        match=np.repeat(np.arange(matches), per),
        files=tuple(Path(f"m{k}.json.xz") for k in range(matches)),
    )


def learned(standing: StandingPositions, **options: int) -> list[PatchBox]:
    with PhysicsWorld(flat_world()) as physics:
        return learn_patches(standing, physics, flat_nav(), **options)


def covered(boxes: list[PatchBox], xy: np.ndarray) -> np.ndarray:
    inside = np.zeros(len(xy), dtype=bool)
    for b in boxes:
        inside |= (
            (xy[:, 0] >= b.x_min)
            & (xy[:, 0] <= b.x_max)
            & (xy[:, 1] >= b.y_min)
            & (xy[:, 1] <= b.y_max)
        )
    return inside


def test_a_box_players_stand_on_in_three_matches_is_one_patch() -> None:
    standing = on_a_surface(matches=3, top_u=40.0)
    boxes = learned(standing)
    assert {b.patch for b in boxes} == {0}
    assert all(b.z_top == 40.0 and b.z_bottom == 0.0 for b in boxes)  # solid down to the floor
    assert all(b.matches == 3 and b.samples == 120 for b in boxes)
    assert covered(boxes, standing.position[:, :2]).all()
    # no more than one column (16 u) beyond the positions on any side
    assert min(b.x_min for b in boxes) >= 500.0 - 32 and max(b.x_max for b in boxes) <= 596 + 32


def test_a_surface_seen_in_one_match_only_is_not_learned() -> None:
    assert learned(on_a_surface(matches=1, top_u=40.0)) == []
    assert len(learned(on_a_surface(matches=1, top_u=40.0), min_matches=1)) > 0


def test_positions_within_a_step_of_the_floor_need_no_patch() -> None:
    assert learned(on_a_surface(matches=3, top_u=12.0)) == []


def test_a_surface_players_stood_under_is_a_slab_and_one_no_one_did_is_solid() -> None:
    high = on_a_surface(matches=3, top_u=200.0)
    assert learned(high) and all(b.z_bottom == 0.0 for b in learned(high))
    below = on_a_surface(matches=3, top_u=0.0)
    walkway = StandingPositions(
        position=np.concatenate([high.position, below.position[::8]]),
        match=np.concatenate([high.match, below.match[::8]]),
        files=high.files,
    )
    boxes = learned(walkway)
    assert boxes and any(b.z_bottom == 200.0 - SLAB_U for b in boxes)


def test_a_sloping_surface_is_not_a_box() -> None:
    ramp = on_a_surface(matches=3, top_u=40.0)
    ramp.position[:, 2] += (ramp.position[:, 0] - 500.0) * 0.5  # rises 48 u over 96 u
    assert learned(ramp) == []


def test_where_more_players_stood_below_than_on_top_there_is_no_box() -> None:
    top = on_a_surface(matches=3, top_u=40.0, side=32.0)
    below = on_a_surface(matches=3, top_u=0.0, side=32.0)
    mixed = StandingPositions(
        position=np.concatenate([top.position, below.position, below.position]),
        match=np.concatenate([top.match, below.match, below.match]),
        files=top.files,
    )
    assert learned(mixed) == []


def test_the_written_file_is_what_the_world_reads(tmp_path: Path) -> None:
    boxes = learned(on_a_surface(matches=3, top_u=40.0))
    path = tmp_path / "world_patches.csv"
    path.write_text(patches_csv(boxes))
    read = read_patches(path, flat_nav())
    expected = [[b.x_min, b.y_min, b.x_max, b.y_max, b.z_top, b.z_bottom] for b in boxes]
    np.testing.assert_allclose(read, expected)
    with open(path, newline="") as f:
        rows = list(csv.DictReader(f))
    assert {"patch", "samples", "matches", "height_spread_u", "above_floor_u"} <= set(rows[0])


# ---- the standing rule and bad input, on ESTA files in the real format ------------------------


def match_with_heights(
    heights: dict[str, list[float]], vertical: dict[str, list[float | None]]
) -> dict:
    """The fixture match with the z and velocityZ of some T players in round 2 replaced, frame
    by frame."""
    document = make_match()
    for index, frame in enumerate(document["gameRounds"][1]["frames"]):
        for player in frame["t"]["players"]:
            if player["name"] in heights:
                player["z"] = heights[player["name"]][index]
                player["velocityZ"] = vertical[player["name"]][index]
    return document


ARC_U = [10.0, 45.5, 62.5, 47.5, 11.0, 0.0]
"""A jump lasting longer than the frames' half second: in the air in frames 1 to 3."""
ARC_VZ = [0.0, 180.2, 20.5, -150.3, 0.0, 0.0]
STEADY_HEIGHT_U = 77.5


@pytest.mark.parametrize("with_velocity", [True, False], ids=["velocityZ", "no velocityZ"])
def test_a_jump_arc_is_not_standing_and_a_steady_height_is(
    tmp_path: Path, with_velocity: bool
) -> None:
    first, second = (name for name, _ in T_PLAYERS[:2])
    vertical: dict[str, list[float | None]] = {
        first: list(ARC_VZ) if with_velocity else [None] * 6,
        second: [0.0] * 6 if with_velocity else [None] * 6,
    }
    document = match_with_heights({first: ARC_U, second: [STEADY_HEIGHT_U] * 6}, vertical)
    path = write_match(tmp_path / "m.json.xz", document)
    standing, _ = read_positions([path], "de_dust2", load_navmesh("de_dust2"))
    heights = standing.position[:, 2]
    assert not np.isin(ARC_U[1:4], heights).any()
    assert np.sum(heights == STEADY_HEIGHT_U) == 6


def test_a_match_of_another_map_is_an_error_naming_the_file(tmp_path: Path) -> None:
    document = make_match()
    document["mapName"] = "de_mirage"
    path = write_match(tmp_path / "mirage.json.xz", document)
    with pytest.raises(WorldError, match=r"mirage\.json\.xz: a de_mirage match"):
        read_positions([path], "de_dust2", load_navmesh("de_dust2"))


def in_metres(document: dict) -> dict:
    for round_ in document["gameRounds"]:
        for frame in round_["frames"]:
            for side in ("t", "ct"):
                for player in frame[side]["players"]:
                    for key in ("x", "y", "z"):
                        player[key] *= HAMMER_TO_M
    return document


def test_positions_in_the_wrong_units_are_an_error_naming_the_file(tmp_path: Path) -> None:
    path = write_match(tmp_path / "metres.json.xz", in_metres(make_match()))
    with pytest.raises(WorldError, match=r"metres\.json\.xz: .*wrong units"):
        read_positions([path], "de_dust2", load_navmesh("de_dust2"))


def test_the_command_fails_in_one_line_and_writes_nothing(tmp_path: Path) -> None:
    document = make_match()
    document["mapName"] = "de_mirage"
    data = write_match(tmp_path / "mirage.json.xz", document)
    out = tmp_path / "out" / "g.npz"
    result = runner.invoke(
        app, ["build-waypoints", "--learn-patches", str(data), "--out", str(out), "--no-plot"]
    )
    assert result.exit_code == 1, result.output
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("error: "), result.stderr
    assert "mirage.json.xz" in lines[0]
    assert not any((tmp_path / "out").iterdir()) if (tmp_path / "out").exists() else True


# ---- the real T-side data -------------------------------------------------------------------


@pytest.mark.skipif(not TSIDE.is_dir(), reason=f"real data not present ({TSIDE})")
def test_learning_on_real_matches_builds_a_graph_that_carries_its_patches(tmp_path: Path) -> None:
    files = sorted(TSIDE.glob("*.json.xz"))[:3]
    folder = tmp_path / "data"
    folder.mkdir()
    for file in files:
        (folder / file.name).symlink_to(file)
    out = tmp_path / "g.npz"
    # A 1.0 m lattice, not the default 0.7 m: the graph is built twice (without and with the
    # candidates) and a coarser lattice builds in about half the time. On these three matches
    # it learns the same candidates and keeps every one, as 0.7 m does, so the graph written
    # is the one the check built; coarser still, the lattice's own zig-zag lengthens paths
    # enough to leave patches out (a third build, and a verdict about the lattice).
    result = runner.invoke(
        app,
        [
            "build-waypoints",
            "--learn-patches",
            str(folder),
            "--out",
            str(out),
            "--no-plot",
            "--spacing",
            "1.0",
        ],
        env={"COLUMNS": "200"},
    )
    assert result.exit_code == 0, result.output
    patches = out.with_suffix(".patches.csv")
    assert "learned" in result.output and str(patches) in result.output.replace("\n", "")
    assert "real consecutive-frame paths" in result.output
    assert re.search(r"nav coverage: [\d.]+% of", result.output)  # a built-in map's build says it
    with open(patches, newline="") as f:
        rows = list(csv.DictReader(f))
    assert rows and all(int(r["matches"]) >= 2 for r in rows)
    assert all(r["paths_lengthened"].isdigit() and r["positions_gained"].isdigit() for r in rows)
    graph = WaypointGraph.load(out)
    assert len(graph.meta["patches"]) == len(rows)
    world = graph_world(graph)
    assert world.meta["patches"] == len(rows)
    # a replay on this graph runs on the world the graph was built on
    replay = runner.invoke(
        app,
        ["replay", f"{files[0]}:2", "--graph", str(out), "--out", str(tmp_path / "replay")],
    )
    assert replay.exit_code == 0, replay.output
    summary = json.loads((tmp_path / "replay" / "summary.json").read_text())
    assert summary["world"] == graph.world_source != ""


def test_tracks_run_player_by_player_and_break_at_a_death_and_a_round() -> None:
    """`follows` joins only a player's consecutive alive frames of one round."""
    alive = np.array([[True, True, False, True], [True, True, True, True]])
    position = np.arange(2 * 4 * 3, dtype=float).reshape(2, 4, 3)
    position[1, 3] = np.nan  # a frame without a position: not a track position
    one = SimpleNamespace(alive=alive, position=position)
    two = SimpleNamespace(alive=np.array([[True, True]]), position=np.ones((1, 2, 3)))
    points, follows = _match_tracks(SimpleNamespace(rounds=[one, two]))  # type: ignore[arg-type]
    expected = [position[0, 0], position[0, 1], position[0, 3], *position[1, :3], [1, 1, 1]]
    np.testing.assert_array_equal(points, np.array([*expected, [1, 1, 1]]))
    assert follows.tolist() == [False, True, False, False, True, True, False, True]
