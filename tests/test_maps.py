"""Every ESTA map works like de_dust2: a synthetic sample is made, evaluated with combat and bomb
on, and replayed; the env plays on it; map names are checked; the floor-aware snap keeps nuke's
stacked bomb sites apart; a bad nav file is one error line."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import numpy as np
import pytest
from scipy.spatial import cKDTree
from typer.testing import CliRunner

from decoy_cli.cli import app
from decoy_cli.csgo import MAP_NAMES
from decoy_cli.env import DecoyParallelEnv
from decoy_cli.errors import GraphError, WorldError
from decoy_cli.esta import read_match
from decoy_cli.waypoints.build import builtin_graph, canonical_map
from decoy_cli.world.nav_data import read_navmesh, read_patches
from decoy_cli.world.navmesh import asset_dir, load_navmesh

runner = CliRunner()
WIDE = {"COLUMNS": "220"}


@pytest.mark.parametrize("map_name", MAP_NAMES)
def test_a_synthetic_sample_of_every_map_is_evaluated_and_replayed(
    tmp_path: Path, map_name: str
) -> None:
    short = map_name.removeprefix("de_")
    made = runner.invoke(
        app,
        ["make-sample", "--map", short, "--rounds", "2", "--seed", "3", "--out", str(tmp_path)],
        env=WIDE,
    )
    assert made.exit_code == 0, made.output
    sample = tmp_path / f"synthetic-{short}-seed3.json.xz"
    match = read_match(sample)
    assert match.map_name == map_name and len(match.rounds) == 2
    assert f"--map {short}" in match.meta["provenance"]["command"] or short == "dust2"
    for round_ in match.rounds:  # both teams move, and the T reach a bomb site's zone or die
        assert round_.num_frames > 20
        assert np.ptp(round_.position[:, :, 0], axis=1).max() > 10.0

    out = tmp_path / "evaluation"
    evaluated = runner.invoke(
        app, ["evaluate", str(sample), "--map", short, "--out", str(out)], env=WIDE
    )
    assert evaluated.exit_code == 0, evaluated.output
    summary = json.loads((out / "summary.json").read_text())
    assert summary["options"]["map"] == map_name
    assert summary["options"]["combat"] is True and summary["options"]["bomb"] is True
    assert summary["counts"]["rounds_evaluated"] == 2 and summary["counts"]["failures"] == 0
    assert summary["counts"]["rounds_both_teams"] == 2

    replayed = runner.invoke(
        app, ["replay", f"{sample}:1", "--out", str(tmp_path / "replay")], env=WIDE
    )
    assert replayed.exit_code == 0, replayed.output
    assert (tmp_path / "replay" / "paths.png").is_file()


@pytest.mark.parametrize("map_name", MAP_NAMES)
def test_the_environment_plays_every_map(map_name: str) -> None:
    env = DecoyParallelEnv(map=map_name.removeprefix("de_"), damage_model=None)
    try:
        observations, infos = env.reset(seed=0)
        assert env.graph.meta["map"] == map_name
        assert env.setup.map_name == map_name  # the damage models' map one-hot
        assert env.metadata["name"] == f"decoy_{map_name.removeprefix('de_')}_v0"
        rng = np.random.default_rng(0)
        for _ in range(20):
            actions = {}
            for name in env.agents:
                if infos[name]["needs_decision"]:
                    allowed = np.flatnonzero(observations[name]["action_mask"])
                    actions[name] = int(rng.choice(allowed))
            observations, _, _, _, infos = env.step(actions)
            if not env.agents:
                break
    finally:
        env.close()


def test_map_names() -> None:
    assert canonical_map("mirage") == canonical_map("DE_MIRAGE") == "de_mirage"
    with pytest.raises(GraphError, match="unknown map 'cache'; this decoy knows: ancient, dust2"):
        canonical_map("cache")
    with pytest.raises(ValueError, match="unknown map 'cache'"):
        DecoyParallelEnv(map="cache")
    with pytest.raises(ValueError, match="given with a graph of de_dust2"):
        DecoyParallelEnv(map="nuke", graph=builtin_graph("dust2"))


def test_nuke_stacked_sites_snap_to_their_own_floor() -> None:
    """Nuke's B site lies under its A site: positions standing on either floor (and up to a
    jump above it) snap to a waypoint of that floor, never to the other one. (Beside the vents,
    whose crawlway opens 0.6 m above B's floor, a position a jump above B snaps to the vents:
    a floor within a jump, which is right.)"""
    graph = builtin_graph("nuke")
    a_nodes, b_nodes = graph.region_of("bombsite_a"), graph.region_of("bombsite_b")
    pos = graph.positions
    gap = np.median(pos[a_nodes, 2]) - np.median(pos[b_nodes, 2])
    assert gap > 5.0  # metres between the two floors
    under = cKDTree(pos[a_nodes, :2]).query(pos[b_nodes, :2], distance_upper_bound=0.5)[0]
    stacked = b_nodes[np.isfinite(under)]
    assert len(stacked) >= 50  # B waypoints with an A waypoint right above them
    over = cKDTree(pos[b_nodes, :2]).query(pos[a_nodes, :2], distance_upper_bound=0.5)[0]
    above = a_nodes[np.isfinite(over)]
    for nodes, floor, other in ((stacked, b_nodes, a_nodes), (above, a_nodes, b_nodes)):
        for lift in (0.0, 0.3, 0.9):
            points = pos[nodes] + np.array([0.2, -0.1, lift])
            index, _ = graph.nearest(points)
            assert not np.isin(index, other).any()
            own = np.isin(index, floor) | (np.abs(pos[index, 2] - pos[nodes, 2]) < 0.6)
            assert np.all(own if lift < 0.9 else own | (np.abs(pos[index, 2] - points[:, 2]) < 0.6))


@pytest.mark.parametrize(
    ("damage", "fragment"),
    [
        (lambda text: text.replace(",0.03125,", ",,", 1), "line 2: an area needs an id"),
        (lambda text: text.replace(",0.03125,", ",high,", 1), "line 2: an area needs an id"),
    ],
)
def test_a_nav_file_with_missing_corner_heights_is_one_error(
    tmp_path: Path, damage, fragment: str
) -> None:
    folder = tmp_path / "de_dust2"
    shutil.copytree(asset_dir("de_dust2"), folder)
    areas = folder / "nav_areas.csv"
    areas.write_text(damage(areas.read_text()))
    with pytest.raises(WorldError, match=fragment):
        read_navmesh(folder)
    (folder / "map.json").write_text("{}")
    with pytest.raises(WorldError, match="not a readable map folder"):
        read_navmesh(folder)


@pytest.mark.parametrize(
    ("row", "fragment"),
    [
        ("-364,1350,-259,,-69,-142,x", "a patch needs numbers"),
        ("-364,1350,-259,1400,-142,-69,x", "an empty or upside-down box"),
        ("90000,1350,90100,1400,-69,-142,x", "the box lies off the map's nav mesh"),
    ],
)
def test_a_bad_patch_row_is_one_error_naming_file_and_line(
    tmp_path: Path, row: str, fragment: str
) -> None:
    path = tmp_path / "world_patches.csv"
    shipped = asset_dir("de_dust2") / "world_patches.csv"
    rows = len(read_patches(shipped, load_navmesh()))
    path.write_text(shipped.read_text().rstrip("\n") + "\n" + row + "\n")
    line = rows + 2  # after the header and the shipped rows
    with pytest.raises(WorldError, match=f"line {line}: {fragment}"):
        read_patches(path, load_navmesh("de_dust2"))
