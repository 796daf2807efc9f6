"""`--sight-mesh`: line of sight tested in a map's own geometry instead of the nav world.

A hand-made mesh (Hammer units, z up, as awpy's `.tri`): a floor far below that spans the map,
and optionally a wall between two players who see each other in the nav world.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from both_teams import BothTeams, Mate
from typer.testing import CliRunner
from worlds import write_awmh

from decoy_cli.cli import app
from decoy_cli.errors import WorldError
from decoy_cli.esta import read_match
from decoy_cli.replay.replayer import ReplayOptions, replay_round
from decoy_cli.sim.combat import CombatBatch, DamageResult
from decoy_cli.waypoints.build import builtin_graph, graph_world
from decoy_cli.world.meshfile import read_mesh, write_obj
from decoy_cli.world.occlusion import read_sight_scene
from decoy_cli.world.world import World


class AlwaysGrazes:
    """Every visible attacker hits for 1 HP (a damage model for tests)."""

    def __call__(self, batch: CombatBatch, rng: np.random.Generator) -> DamageResult:
        k = len(batch)
        return DamageResult(np.ones(k, np.int64), np.full(k, 2), np.ones(k, bool))


def facing() -> tuple[BothTeams, np.ndarray, np.ndarray]:
    """A T and a CT standing in bomb site A in sight of each other, and their feet (metres)."""
    graph = builtin_graph()
    a = graph.region_of("bombsite_a")
    doc = BothTeams(
        frames=8,
        players=[Mate("t1", "T", [int(a[0])]), Mate("ct1", "CT", [int(a[3])])],
    )
    return doc, graph.positions[int(a[0])], graph.positions[int(a[3])]


def write_mesh(path: Path, wall_between: tuple[np.ndarray, np.ndarray] | None) -> Path:
    """The graph's own nav world as an .obj in Hammer units, with a wall 40 m wide and tall
    across the middle of the segment between two feet when given."""
    triangles = graph_world(builtin_graph()).triangles
    if wall_between is not None:
        a, b = wall_between
        middle = (a + b) / 2
        across = np.array([-(b - a)[1], (b - a)[0], 0.0])
        across = 20.0 * across / np.linalg.norm(across)
        up = np.array([0.0, 0.0, 20.0])
        corners = [middle - across - up, middle + across - up, middle + across + up]
        far = middle - across + up
        wall = np.array([corners, [corners[0], corners[2], far]])
        triangles = np.concatenate([triangles, wall])
    write_obj(World(triangles, name="test", source=str(path)), path)
    return path


def hits(doc: BothTeams, tmp_path: Path, mesh: Path | None) -> int:
    round_ = read_match(doc.write(tmp_path / "m.json")).rounds[0]
    graph = builtin_graph()
    scene = read_sight_scene(mesh, graph.positions, "de_dust2") if mesh is not None else None
    options = ReplayOptions(damage_model=AlwaysGrazes(), bomb=False, sight=scene)
    result = replay_round(round_, graph, options)
    return sum(e.kind == "damage" for e in result.events)


def test_a_wall_of_the_sight_mesh_blocks_what_the_nav_world_sees(tmp_path: Path) -> None:
    doc, t_feet, ct_feet = facing()
    assert hits(doc, tmp_path, None) > 0  # the nav world: they see each other
    open_mesh = write_mesh(tmp_path / "open.obj", None)
    assert hits(doc, tmp_path, open_mesh) > 0  # nothing between them in this mesh either
    walled = write_mesh(tmp_path / "walled.obj", (t_feet, ct_feet))
    assert hits(doc, tmp_path, walled) == 0


def test_an_awpy3_mesh_is_taken_as_the_sight_mesh(tmp_path: Path) -> None:
    """The same walled geometry written as awpy 3's `.mesh` blocks the same shots."""
    doc, t_feet, ct_feet = facing()
    walled = tmp_path / "walled.mesh"
    write_awmh(read_mesh(write_mesh(tmp_path / "walled.obj", (t_feet, ct_feet))), walled)
    assert hits(doc, tmp_path, walled) == 0


def test_a_mesh_of_another_place_or_size_is_refused(tmp_path: Path) -> None:
    feet = builtin_graph().positions
    small = tmp_path / "small.obj"
    small.write_text("v 0 0 0\nv 10 0 0\nv 0 10 0\nf 1 2 3\n")
    with pytest.raises(WorldError, match="a floor under 0% of de_dust2's waypoints"):
        read_sight_scene(small, feet, "de_dust2")
    huge = tmp_path / "huge.obj"
    huge.write_text("v -1e30 -1e30 0\nv 1e30 -1e30 0\nv 0 1e30 0\nf 1 2 3\n")
    with pytest.raises(WorldError, match="too large for a map"):
        read_sight_scene(huge, feet, "de_dust2")
    moved = tmp_path / "moved.obj"  # the right map, 10 m too high (another offset or version)
    world = graph_world(builtin_graph())
    write_obj(
        World(world.triangles + np.array([0.0, 0.0, 10.0]), name="m", source=str(moved)), moved
    )
    with pytest.raises(WorldError, match="a floor under 0%"):
        read_sight_scene(moved, feet, "de_dust2")


def test_the_commands_take_it_name_it_and_refuse_a_bad_one(tmp_path: Path) -> None:
    doc, t_feet, ct_feet = facing()
    match = doc.write(tmp_path / "m.json")
    walled = write_mesh(tmp_path / "walled.obj", (t_feet, ct_feet))
    runner = CliRunner()
    out = tmp_path / "replay"
    result = runner.invoke(
        app, ["replay", f"{match}:5", "--no-bomb", "--sight-mesh", str(walled), "--out", str(out)]
    )
    assert result.exit_code == 0, result.output
    summary = json.loads((out / "summary.json").read_text())
    assert summary["line_of_sight_in"].startswith(f"{walled.resolve()} (sha256 ")
    small = tmp_path / "small.obj"
    small.write_text("v 0 0 0\nv 10 0 0\nv 0 10 0\nf 1 2 3\n")
    for command in (["replay", f"{match}:5"], ["evaluate", str(match)]):
        result = runner.invoke(app, [*command, "--sight-mesh", str(small), "--out", str(out)])
        assert result.exit_code == 1
        assert result.output.startswith("error: ") and result.output.count("\n") == 1
        assert "a floor under 0%" in result.output
    for command in (["replay", f"{match}:5"], ["evaluate", str(match)]):  # nothing to see for
        for off in (["--no-combat"], ["--models", "none"]):
            result = runner.invoke(app, [*command, *off, "--sight-mesh", str(walled)])
            errors = [line for line in result.output.splitlines() if line.startswith("error:")]
            assert result.exit_code == 1 and len(errors) == 1
            assert errors[0].startswith("error: a sight mesh is where line of sight")
    evaluated = tmp_path / "evaluated"
    result = runner.invoke(
        app,
        [
            "evaluate",
            str(match),
            "--no-bomb",
            "--workers",
            "1",
            "--no-view",
            "--sight-mesh",
            str(walled),
            "--out",
            str(evaluated),
        ],
    )
    assert result.exit_code == 0, result.output
    report = (evaluated / "report.md").read_text()
    assert f"--sight-mesh {walled}" in report and "line of sight in" in report
