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

from decoy_cli.cli import app
from decoy_cli.csgo import HAMMER_TO_M
from decoy_cli.errors import WorldError
from decoy_cli.esta import read_match
from decoy_cli.replay.replayer import ReplayOptions, replay_round
from decoy_cli.sim.combat import CombatBatch, DamageResult
from decoy_cli.sim.sight import read_sight_mesh
from decoy_cli.waypoints.build import builtin_graph
from decoy_cli.world.occlusion import OcclusionScene


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


def quad(corners: list[np.ndarray]) -> list[str]:
    """Two triangles of an .obj face, corners in metres written in Hammer units."""
    return [f"v {' '.join(f'{c / HAMMER_TO_M:.3f}' for c in corner)}" for corner in corners]


def write_mesh(path: Path, wall_between: tuple[np.ndarray, np.ndarray] | None) -> Path:
    """A floor 50 m under the map spanning its waypoints, and a wall across the middle of the
    segment between two feet when given."""
    positions = builtin_graph().positions
    low, high = positions.min(axis=0) - 5.0, positions.max(axis=0) + 5.0
    z = low[2] - 50.0
    vertices = quad(
        [
            np.array(c)
            for c in [
                (low[0], low[1], z),
                (high[0], low[1], z),
                (high[0], high[1], z),
                (low[0], high[1], z),
            ]
        ]
    )
    if wall_between is not None:
        a, b = wall_between
        middle = (a + b) / 2
        across = np.array([-(b - a)[1], (b - a)[0], 0.0])
        across = 20.0 * across / np.linalg.norm(across)
        up = np.array([0.0, 0.0, 20.0])
        vertices += quad(
            [middle - across - up, middle + across - up, middle + across + up, middle - across + up]
        )
    faces = [
        f"f {4 * q + 1} {4 * q + 2} {4 * q + 3}\nf {4 * q + 1} {4 * q + 3} {4 * q + 4}"
        for q in range(len(vertices) // 4)
    ]
    path.write_text("\n".join([*vertices, *faces]) + "\n")
    return path


def hits(doc: BothTeams, tmp_path: Path, mesh: Path | None) -> int:
    round_ = read_match(doc.write(tmp_path / "m.json")).rounds[0]
    graph = builtin_graph()
    scene = OcclusionScene(read_sight_mesh(mesh, graph)) if mesh is not None else None
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


def test_a_mesh_that_does_not_span_the_map_is_refused(tmp_path: Path) -> None:
    small = tmp_path / "small.obj"
    small.write_text("v 0 0 0\nv 10 0 0\nv 0 10 0\nf 1 2 3\n")
    with pytest.raises(WorldError, match="spans 0% of de_dust2's waypoints"):
        read_sight_mesh(small, builtin_graph())


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
    assert summary["line_of_sight_in"] == str(walled)
    small = tmp_path / "small.obj"
    small.write_text("v 0 0 0\nv 10 0 0\nv 0 10 0\nf 1 2 3\n")
    for command in (["replay", f"{match}:5"], ["evaluate", str(match)]):
        result = runner.invoke(app, [*command, "--sight-mesh", str(small), "--out", str(out)])
        assert result.exit_code == 1
        assert result.output.startswith("error: ") and result.output.count("\n") == 1
        assert "spans 0%" in result.output
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
