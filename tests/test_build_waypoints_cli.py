"""`decoy build-waypoints`: the shipped graph is current, outputs, user meshes, and every bad
input ends as one `error: ...` line with exit code 1 and no half-written file."""

from __future__ import annotations

import re
import warnings
from pathlib import Path

import numpy as np
import pytest
from differences import npz_difference
from esta_fixtures import write_match
from shipped_graphs import assert_rebuilt_when_inputs_changed, graph_stamps
from typer.testing import CliRunner, Result
from worlds import fixture_room, room, seeds_of

from decoy_cli.cli import app
from decoy_cli.csgo import MAP_NAMES
from decoy_cli.waypoints.build import GRAPH_FILE, build_graph, builtin_graph, graph_world
from decoy_cli.waypoints.coverage import nav_coverage
from decoy_cli.waypoints.graph import WaypointGraph
from decoy_cli.waypoints.quality import alignment_quality
from decoy_cli.world.meshfile import read_mesh, write_obj, write_tri
from decoy_cli.world.navmesh import REGIONS, asset_dir, load_navmesh
from decoy_cli.world.world import World

DATA = Path(__file__).resolve().parents[1].parent / "shared" / "data"
TSIDE = DATA / "esta_dust2_tside"
SHIPPED = asset_dir() / GRAPH_FILE

runner = CliRunner()
WIDE = {"COLUMNS": "200"}


def build(*args: str) -> Result:
    return runner.invoke(app, ["build-waypoints", *args], env=WIDE)


def seed_arg(world: World) -> list[str]:
    return ["--seed", ",".join(f"{v:g}" for v in world.meta["seed"])]


def assert_one_error_line(result: Result, *fragments: str) -> None:
    """Exit code 1, exactly one `error: ...` line on stderr, no traceback."""
    assert result.exit_code == 1, result.output
    assert isinstance(result.exception, SystemExit)
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("error: "), result.stderr
    assert "Traceback" not in result.output
    for fragment in fragments:
        assert fragment in lines[0], lines[0]


def small_room() -> World:
    """A 6.3 m square room (a map is at least 5 m across); lattice lines 0.35 m from the walls."""
    return room(6.3, 6.3)


@pytest.fixture(scope="module")
def small_obj(tmp_path_factory: pytest.TempPathFactory) -> Path:
    path = tmp_path_factory.mktemp("mesh") / "small.obj"
    write_obj(small_room(), path)
    return path


@pytest.fixture(scope="module")
def fixture_obj(tmp_path_factory: pytest.TempPathFactory) -> Path:
    path = tmp_path_factory.mktemp("mesh") / "fixture_room.obj"
    write_obj(fixture_room(), path)
    return path


@pytest.fixture(scope="module")
def esta_match(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return write_match(tmp_path_factory.mktemp("esta") / "fixture.json.xz")


# ---- the built-in map (one full build with every check on its output) -------------------------


def test_builtin_build(tmp_path: Path, subtests: pytest.Subtests) -> None:
    """THE test that the shipped graph is current: rebuilding it gives the same bytes.

    The build runs once; its table, plot and (when the real data is present) the alignment
    check on real T-side positions are checked on the same run. As for the other shipped
    graphs, it runs when the fingerprint of the build's inputs differs from the stamp of the
    last rebuild found equal (scripts/graph_stamps.py): while it is the same, the rebuild
    cannot differ, and what the build reports of the graph is checked on the shipped graph
    (`test_every_shipped_graph_has_its_regions_and_covers_its_nav`,
    `test_the_shipped_graph_holds_the_real_t_side_positions`).
    """
    if graph_stamps().stamp_is_current("de_dust2", GRAPH_FILE):
        pytest.skip("inputs unchanged since the rebuild was checked (scripts/graph_stamps.py)")
    out = tmp_path / "dust2.npz"
    args = ["--out", str(out)]
    if TSIDE.is_dir():
        args += ["--check-esta", str(TSIDE)]
    result = build(*args)
    assert result.exit_code == 0, result.output

    with subtests.test("the shipped graph is reproduced byte for byte"):
        assert out.read_bytes() == SHIPPED.read_bytes(), npz_difference(out, SHIPPED)

    with subtests.test("summary table, graph file and plot"):
        graph = WaypointGraph.load(out)
        for stage in ("lattice (BFS)", "drop pass", "verification", "pruning", "graph"):
            assert stage in result.stdout
        assert f"{graph.num_nodes:,} nodes, {graph.num_edges:,} edges" in result.stdout
        assert "built-in de_dust2 nav mesh" in result.stdout
        assert f"graph written to {out}" in result.stdout
        png = out.with_suffix(".png")
        assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n" and png.stat().st_size > 50_000
        assert sorted(p.name for p in tmp_path.iterdir()) == ["dust2.npz", "dust2.png"]
        assert result.stderr == ""
        found = re.search(r"nav coverage: ([\d.]+)% of", result.stdout)
        assert found and float(found.group(1)) / 100 >= COVERAGE_TARGET

    with subtests.test("--check-esta on the real T-side positions"):
        if not TSIDE.is_dir():
            pytest.skip(f"real ESTA data not found at {TSIDE}")
        count = re.search(r"alignment: ([\d,]+) alive positions", result.stdout)
        assert count and int(count.group(1).replace(",", "")) > 100_000
        row = re.search(r"horizontal\s*│\s*([\d.]+)\s*│\s*([\d.]+)\s*│\s*([\d.]+)%", result.stdout)
        assert row, result.stdout
        median, p95, within = (float(v) for v in row.groups())
        assert median < 0.35 and p95 < 0.8 and within >= 90.0
        assert "no waypoint on their floor" in result.stdout
    stale = "de_dust2/waypoints.npz: stamp stale; run python scripts/graph_stamps.py"
    warnings.warn(stale, stacklevel=2)


@pytest.mark.skipif(not TSIDE.is_dir(), reason=f"real ESTA data not found at {TSIDE}")
def test_the_shipped_graph_holds_the_real_t_side_positions() -> None:
    """What `--check-esta` reports of the real T-side positions on the shipped graph."""
    graph = builtin_graph()
    quality = alignment_quality(graph, np.zeros((0, 3)), graph_world(graph), TSIDE)
    assert quality.positions > 100_000
    assert quality.median_horizontal < 0.35 and quality.p95_horizontal < 0.8
    assert quality.within_horizontal >= 0.90


# ---- the other built-in maps ---------------------------------------------------------------------

COVERAGE_TARGET = 0.98
"""Share of a map's nav-mesh floor (by area) within 0.5 m of a waypoint (issue 16's target)."""

COVERAGE_BELOW_TARGET = {"de_inferno": 0.95, "de_nuke": 0.88}
"""Maps that miss the target today, with the floor they must not fall below: nuke's roofs,
silo and heaven are reached by ladders, which awpy's nav data lacks; inferno's library, deck
and balcony are cut off by wall faces the nav world puts across their doorways."""


OTHER_MAPS = [m for m in MAP_NAMES if m != "de_dust2"]


@pytest.mark.parametrize("map_name", MAP_NAMES)
def test_every_shipped_graph_has_its_regions_and_covers_its_nav(map_name: str) -> None:
    """Both spawns and both bomb sites have waypoints; the graph covers the nav mesh's floor
    as the build reports it (`nav_coverage`)."""
    graph = builtin_graph(map_name)
    assert all(len(graph.region_of(r)) >= 20 for r in REGIONS)
    covered = nav_coverage(graph, load_navmesh(map_name)).covered
    assert covered >= COVERAGE_BELOW_TARGET.get(map_name, COVERAGE_TARGET)


@pytest.mark.parametrize("map_name", OTHER_MAPS)
def test_every_other_shipped_graph_is_current(tmp_path: Path, map_name: str) -> None:
    """Rebuilding a map's graph gives the shipped bytes. The build is deterministic: while the
    fingerprint of its inputs is the one stamped when its bytes were last rebuilt and found
    equal (scripts/graph_stamps.py), the rebuild cannot differ and is not run."""
    assert_rebuilt_when_inputs_changed(map_name, GRAPH_FILE, tmp_path)


# ---- user meshes -------------------------------------------------------------------------------


def test_user_obj_mesh_matches_the_library_build(tmp_path: Path, fixture_obj: Path) -> None:
    out = tmp_path / "room.npz"
    result = build(
        "--mesh", str(fixture_obj), *seed_arg(fixture_room()), "--out", str(out), "--no-plot"
    )
    assert result.exit_code == 0, result.output
    assert sorted(p.name for p in tmp_path.iterdir()) == ["room.npz"]  # --no-plot: no PNG
    assert "plot written" not in result.stdout
    world = read_mesh(fixture_obj)
    expected, _ = build_graph(world, seeds=seeds_of(fixture_room()))
    expected.save(tmp_path / "library.npz")
    assert out.read_bytes() == (tmp_path / "library.npz").read_bytes()
    graph = WaypointGraph.load(out)
    # lattice lines -7 + 0.7 k (k = -20..20) by 12 + 0.7 k (k = -6..6), all clear of the walls
    assert graph.num_nodes == 41 * 13
    assert "533 nodes" in result.stdout and f"waypoints of {fixture_obj}" in result.stdout


def test_user_tri_mesh_with_plot(tmp_path: Path) -> None:
    mesh = tmp_path / "small.tri"
    write_tri(small_room(), mesh)
    out = tmp_path / "out" / "small.npz"
    result = build("--mesh", str(mesh), *seed_arg(small_room()), "--out", str(out))
    assert result.exit_code == 0, result.output
    assert WaypointGraph.load(out).num_nodes == 81
    assert (tmp_path / "out" / "small.png").read_bytes()[:4] == b"\x89PNG"
    assert sorted(p.name for p in (tmp_path / "out").iterdir()) == ["small.npz", "small.png"]


def test_user_mesh_in_metres_with_offset(tmp_path: Path) -> None:
    mesh = tmp_path / "small_m.obj"
    write_obj(small_room(), mesh, units="m")
    out = tmp_path / "g.npz"
    result = build(
        "--mesh", str(mesh), "--units", "m", "--offset", "10,20,1", "--seed", "13.15,23.15,1",
        "--out", str(out), "--no-plot",
    )  # fmt: skip
    assert result.exit_code == 0, result.output
    graph = WaypointGraph.load(out)
    assert graph.num_nodes == 81
    np.testing.assert_allclose(graph.positions[:, 2], 1.0, atol=1e-6)
    assert graph.positions[:, 0].min() > 10.0 and graph.positions[:, 1].min() > 20.0


def test_check_esta_on_the_fixture_passes(tmp_path: Path, fixture_obj, esta_match) -> None:
    """The fixture room lies under every fixture player, so all of them snap within 0.5 m."""
    result = build(
        "--mesh", str(fixture_obj), *seed_arg(fixture_room()), "--out", str(tmp_path / "g.npz"),
        "--no-plot", "--check-esta", str(esta_match),
    )  # fmt: skip
    assert result.exit_code == 0, result.output
    assert re.search(r"alignment: \d+ alive positions", result.stdout)
    row = re.search(r"horizontal\s*│\s*([\d.]+)\s*│\s*([\d.]+)\s*│\s*([\d.]+)%", result.stdout)
    assert row and float(row.group(3)) == 100.0
    assert "no waypoint on their floor: 0;" in result.stdout


@pytest.mark.filterwarnings("error")  # a numpy warning would be a stray line on the terminal
def test_check_esta_misaligned_mesh_fails(tmp_path: Path, fixture_obj, esta_match) -> None:
    """The same room lifted 5 m: no fixture player is on its floor."""
    args = [
        "--mesh", str(fixture_obj), "--offset", "0,0,5", "--seed", "-7,12,5",
        "--out", str(tmp_path / "g.npz"), "--no-plot", "--check-esta", str(esta_match),
    ]  # fmt: skip
    result = build(*args)
    assert_one_error_line(result, "of the positions lie within 0.5 m", "misaligned")
    assert "alignment:" in result.stdout
    # with --min-aligned 0 the same check only reports
    result = build(*args, "--min-aligned", "0")
    assert result.exit_code == 0, result.output
    assert re.search(r"horizontal\s*│\s*nan\s*│\s*inf\s*│\s*0\.00%", result.stdout)
    assert "no waypoint on their floor: 88;" in result.stdout


def test_check_esta_missing_path(tmp_path: Path, small_obj: Path) -> None:
    result = build(
        "--mesh", str(small_obj), *seed_arg(small_room()), "--out", str(tmp_path / "g.npz"),
        "--no-plot", "--check-esta", str(tmp_path / "absent.json.xz"),
    )  # fmt: skip
    assert_one_error_line(result, "absent.json.xz", "no such file")
    assert not (tmp_path / "g.npz").exists()  # refused before the build, not after it


# ---- bad input: one error line ----------------------------------------------------------------


def test_wrong_up_axis(tmp_path: Path, fixture_obj: Path) -> None:
    out = tmp_path / "g.npz"
    result = build("--mesh", str(fixture_obj), "--up-axis", "y", "--out", str(out))
    assert_one_error_line(result, str(fixture_obj), "not Z-up", "--up-axis y")
    assert not out.exists()


def test_wrong_units(tmp_path: Path) -> None:
    mesh = tmp_path / "metres.obj"
    write_obj(fixture_room(), mesh, units="m")
    result = build("--mesh", str(mesh), "--out", str(tmp_path / "g.npz"))  # read as Hammer
    assert_one_error_line(result, "too small for a map", "--units m")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["metres.obj"]


@pytest.mark.parametrize(
    ("name", "content", "fragment"),
    [
        ("absent.obj", None, "no such mesh file"),
        ("cut.tri", b"\0" * 35, "not a multiple of 36"),
        ("bad.obj", b"v 0 0 0\nv 1 0 x\nv 0 1 0\nf 1 2 3\n", "line 2"),
        ("faces.obj", b"v 0 0 0\nf 1 2 3\n", "face refers to vertex 2"),
        ("mesh.stl", b"solid", "unknown mesh format"),
    ],
)
def test_missing_or_corrupt_mesh(tmp_path: Path, name: str, content, fragment: str) -> None:
    mesh = tmp_path / name
    if content is not None:
        mesh.write_bytes(content)
    result = build("--mesh", str(mesh), "--out", str(tmp_path / "g.npz"))
    assert_one_error_line(result, str(mesh), fragment)


@pytest.mark.parametrize(
    ("args", "fragment"),
    [
        (["--seed", "1,2"], "--seed wants three numbers"),
        (["--seed", "1,2,nan"], "--seed wants three numbers"),
        (["--seed", "40,40,0"], "seed 0 at [40.0, 40.0, 0.0] m is not above a floor"),
        (["--offset", "a,b,c"], "--offset wants three numbers"),
        (["--map", "cache"], "unknown map 'cache'"),
    ],
)
def test_bad_options(tmp_path: Path, small_obj: Path, args: list[str], fragment: str) -> None:
    result = build("--mesh", str(small_obj), "--out", str(tmp_path / "g.npz"), *args)
    assert_one_error_line(result, fragment)
    assert list(tmp_path.iterdir()) == []


def test_manual_waypoints(tmp_path: Path, small_obj: Path) -> None:
    """A manual point inside the room is merged; one off the world stops the build."""
    good = tmp_path / "good.csv"
    good.write_text("x,y,z\n3.5,3.5,0.0\n")
    out = tmp_path / "g.npz"
    result = build("--mesh", str(small_obj), *seed_arg(small_room()), "--manual", str(good),
                   "--out", str(out), "--no-plot")  # fmt: skip
    assert result.exit_code == 0, result.output
    assert "1 added, 0 unlinkable" in result.stdout
    assert WaypointGraph.load(out).num_nodes == 82
    out.unlink()

    off = tmp_path / "off.csv"
    off.write_text("x,y,z\n3.5,3.5,0.0\n40.0,3.0,0.0\n")
    result = build("--mesh", str(small_obj), *seed_arg(small_room()), "--manual", str(off),
                   "--out", str(out), "--no-plot")  # fmt: skip
    assert_one_error_line(result, "manual waypoint 1 at [40.0, 3.0, 0.0] m is not on a floor")
    assert not out.exists()

    bad = tmp_path / "bad.csv"
    bad.write_text("x,y\n1,2\n")
    result = build("--mesh", str(small_obj), "--manual", str(bad), "--out", str(out))
    assert_one_error_line(result, str(bad), "line 2", "columns x, y, z")
    result = build("--mesh", str(small_obj), "--manual", str(tmp_path / "no.csv"))
    assert_one_error_line(result, "cannot read manual waypoints")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["bad.csv", "good.csv", "off.csv"]


@pytest.mark.parametrize("where", ["under-a-file", "a-directory", "png-is-a-directory"])
def test_unwritable_out(tmp_path: Path, small_obj: Path, where: str) -> None:
    """One error line and nothing half-written: no temporary file stays in the folder."""
    folder = tmp_path / "out"
    folder.mkdir()
    if where == "under-a-file":
        (folder / "file").write_text("x")
        out, expected = folder / "file" / "g.npz", ["file"]
    elif where == "a-directory":
        out, expected = folder / "g.npz", ["g.npz"]
        out.mkdir()
    else:  # the graph is written, its picture cannot be
        out, expected = folder / "g.npz", ["g.npz", "g.png"]
        (folder / "g.png").mkdir()
    result = build("--mesh", str(small_obj), *seed_arg(small_room()), "--out", str(out))
    assert_one_error_line(result, "cannot write")
    assert sorted(p.name for p in folder.iterdir()) == expected
    if where == "under-a-file":
        assert (folder / "file").read_text() == "x"
