"""CS2 nav meshes (awpy's JSON form): reading, the polygon world's walls, steps and walkways,
the map check, graphs that carry their world, and `decoy build-waypoints --nav`."""

from __future__ import annotations

import gzip
import json
import lzma
import os
import sys
from pathlib import Path

import numpy as np
import pytest
from nav_binary import write_binary_nav
from shipped_graphs import assert_rebuilt_when_inputs_changed
from typer.testing import CliRunner

from decoy_cli.cli import app
from decoy_cli.csgo import HAMMER_TO_M
from decoy_cli.errors import GraphError, WorldError
from decoy_cli.waypoints.build import (
    CS2_GRAPH_FILE,
    build_graph,
    builtin_graph,
    graph_world,
)
from decoy_cli.waypoints.graph import WaypointGraph
from decoy_cli.waypoints.lattice import LatticeParams
from decoy_cli.world.cs2_world import SAME_MAP_SHARE, cs2_world, on_map_share
from decoy_cli.world.nav_climbs import world_climbs
from decoy_cli.world.nav_data import REGIONS, load_navmesh
from decoy_cli.world.nav_json import PolygonNav, read_nav
from decoy_cli.world.nav_polygons import POLYGON_WALL_PUSH_U, polygon_triangles

DATA = Path(__file__).resolve().parents[1].parent / "shared" / "data"
CS2_NAV = DATA / "cs2_maps" / "de_dust2.nav.json.xz"
runner = CliRunner()


def nav_document(polygons: list[list[tuple[float, float, float]]], **extra: object) -> dict:
    """An awpy JSON nav of the given polygons (Hammer units), each linked to the next."""
    areas = {}
    for k, polygon in enumerate(polygons, start=1):
        areas[str(k)] = {
            "area_id": k,
            "hull_index": 0,
            "dynamic_attribute_flags": 0,
            "corners": [{"x": x, "y": y, "z": z} for x, y, z in polygon],
            "connections": [k + 1] if k < len(polygons) else [],
            "ladders_above": [],
            "ladders_below": [],
        }
    return {"version": 35, "sub_version": 1, "is_analyzed": True, "areas": areas, **extra}


def square(x0: float, y0: float, size: float, z: float) -> list[tuple[float, float, float]]:
    return [(x0, y0, z), (x0 + size, y0, z), (x0 + size, y0 + size, z), (x0, y0 + size, z)]


def write_nav(path: Path, document: dict) -> Path:
    path.write_text(json.dumps(document))
    return path


def triangles_of(tmp_path: Path, polygons: list) -> np.ndarray:
    return polygon_triangles(read_nav(write_nav(tmp_path / "t.json", nav_document(polygons))))


def faces_on_line(tris: np.ndarray, axis: int, value: float, tol: float = 0.5) -> np.ndarray:
    """Vertical triangles lying on the plane `axis` = value (Hammer units)."""
    normal_z = np.cross(tris[:, 1] - tris[:, 0], tris[:, 2] - tris[:, 0])[:, 2]
    vertical = np.abs(normal_z) < 1e-6
    on = np.all(np.abs(tris[:, :, axis] - value) <= tol, axis=1)
    return tris[vertical & on]


# ---- the reader -------------------------------------------------------------------------------


def test_a_nav_reads_plain_xz_and_gzip_alike(tmp_path: Path) -> None:
    text = json.dumps(nav_document([square(0, 0, 100, 0), square(100, 0, 100, 0)]))
    (tmp_path / "a.json").write_text(text)
    (tmp_path / "a.json.xz").write_bytes(lzma.compress(text.encode()))
    (tmp_path / "a.json.gz").write_bytes(gzip.compress(text.encode()))
    navs = [read_nav(tmp_path / name) for name in ("a.json", "a.json.xz", "a.json.gz")]
    for nav in navs:
        assert nav.num_areas == 2 and nav.version == 35
        assert np.array_equal(nav.corners, navs[0].corners)
        assert nav.connections.tolist() == [[0, 1]]


def test_clockwise_corners_are_turned_counter_clockwise(tmp_path: Path) -> None:
    nav = read_nav(write_nav(tmp_path / "c.json", nav_document([square(0, 0, 50, 0)[::-1]])))
    x, y = nav.polygon(0)[:, 0], nav.polygon(0)[:, 1]
    assert np.dot(x, np.roll(y, -1)) - np.dot(np.roll(x, -1), y) > 0


@pytest.mark.parametrize(
    ("change", "message"),
    [
        (lambda d: d.update(version=16), "nav version 16"),
        (lambda d: d.update(version="35"), "nav version '35'"),
        (lambda d: d.update(areas=[]), "no 'areas' object"),
        (lambda d: d.update(areas={}), "0 areas"),
        (lambda d: d["areas"]["1"].update(area_id=7), "the key's whole number"),
        (lambda d: d["areas"]["1"].update(corners=[{"x": 0, "y": 0, "z": 0}]), "3 to 8 points"),
        (lambda d: d["areas"]["1"]["corners"][0].update(x="a"), "numbers x, y and z"),
        (lambda d: d["areas"]["1"]["corners"][0].update(x=1e9), "outside any map"),
        (lambda d: d["areas"]["1"].update(connections=[99]), "names area 99"),
        (lambda d: d["areas"]["1"].update(connections="2"), "list of area ids"),
    ],
)
def test_a_bad_nav_is_one_world_error(tmp_path: Path, change, message: str) -> None:
    document = nav_document([square(0, 0, 100, 0), square(100, 0, 100, 0)])
    change(document)
    with pytest.raises(WorldError, match=message):
        read_nav(write_nav(tmp_path / "bad.json", document))


@pytest.mark.parametrize(
    ("content", "message"),
    [
        (b"\xfd7zXZ\x00broken", "damaged compressed file"),
        (b"\x1f\x8b\x08\x00broken", "damaged compressed file"),
        (b"{not json", "JSON"),
    ],
)
def test_damaged_files_are_one_world_error(tmp_path: Path, content: bytes, message: str) -> None:
    (tmp_path / "bad.json").write_bytes(content)
    with pytest.raises(WorldError, match=message):
        read_nav(tmp_path / "bad.json")


def test_a_compressed_bomb_is_refused_without_unpacking_it(tmp_path: Path) -> None:
    (tmp_path / "bomb.json.xz").write_bytes(lzma.compress(b" " * 70_000_000))
    with pytest.raises(WorldError, match="unpacks to more than"):
        read_nav(tmp_path / "bomb.json.xz")


def test_a_binary_nav_without_awpy_3_says_how_to_read_it(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setitem(sys.modules, "awpy", None)  # as if awpy 3 were not installed
    path = write_binary_nav(tmp_path / "de_dust2.nav", [square(0, 0, 64, 0)], [])
    with pytest.raises(WorldError, match=r"read through awpy 3 .*awpy nav FILE\.nav"):
        read_nav(path)


def same_nav(a: PolygonNav, b: PolygonNav) -> bool:
    return (
        np.array_equal(a.area_id, b.area_id)
        and np.array_equal(a.sides, b.sides)
        and np.array_equal(a.corners, b.corners)
        and np.array_equal(a.connections, b.connections)
        and a.version == b.version
    )


@pytest.mark.parametrize("version", [30, 35, 36])
def test_a_binary_nav_reads_through_awpy3_as_its_json_form(tmp_path: Path, version: int) -> None:
    """A binary nav written in the layout awpy 3 reads (tests/nav_binary.py; no file from the
    game is here) gives the areas, corners and connections of the same nav in JSON form."""
    pytest.importorskip("awpy", reason="awpy 3 (the test extra) reads binary navs")
    polygons = [
        square(0, 0, 64, 0),
        [(64.0, 0.0, 0.0), (128.0, 0.0, 16.0), (64.0, 64.0, 0.0)],  # a sloped triangle
        square(0, 64, 64, 40),
    ]
    links = [(0, 1), (1, 0), (0, 2)]
    binary = read_nav(write_binary_nav(tmp_path / "x.nav", polygons, links, version))
    document = nav_document(polygons)
    for k, area in enumerate(document["areas"].values()):
        area["connections"] = [b + 1 for a, b in links if a == k]
    json_form = read_nav(write_nav(tmp_path / "x.json", {**document, "version": version}))
    assert same_nav(binary, json_form)


@pytest.mark.skipif(not CS2_NAV.is_file(), reason=f"{CS2_NAV} is absent (../shared/data)")
def test_cs2_dust2_as_a_binary_nav_reads_as_its_json_form(tmp_path: Path) -> None:
    pytest.importorskip("awpy", reason="awpy 3 (the test extra) reads binary navs")
    nav = read_nav(CS2_NAV)
    polygons = [nav.polygon(a).tolist() for a in range(nav.num_areas)]
    path = write_binary_nav(
        tmp_path / "de_dust2.nav", polygons, nav.connections.tolist(), area_ids=nav.area_id
    )
    assert same_nav(read_nav(path), nav)
    truncated = tmp_path / "cut.nav"
    truncated.write_bytes(path.read_bytes()[: path.stat().st_size // 2])
    with pytest.raises(WorldError, match=r"cut\.nav: not a CS2 nav file awpy 3 reads"):
        read_nav(truncated)


def test_a_binary_nav_makes_the_world_its_json_form_makes(tmp_path: Path) -> None:
    pytest.importorskip("awpy", reason="awpy 3 (the test extra) reads binary navs")
    piece = read_nav(dust2_piece(tmp_path))
    # the corners as a binary nav holds them (float32), written in both forms
    polygons = [piece.polygon(a).astype(np.float32).tolist() for a in range(piece.num_areas)]
    json_form = write_nav(tmp_path / "f32.json", nav_document(polygons))  # each to the next
    path = write_binary_nav(tmp_path / "piece.nav", polygons, piece.connections.tolist(), 36)
    world = cs2_world(path, "de_dust2")
    assert world.source == "CS2 de_dust2 nav mesh (piece.nav, nav version 36)"
    assert np.array_equal(world.triangles, cs2_world(json_form, "de_dust2").triangles)


@pytest.mark.skipif(
    not os.environ.get("DECOY_TEST_NAV"),
    reason="DECOY_TEST_NAV names no CS2 de_dust2 .nav from the game to read through awpy 3",
)
def test_a_real_binary_nav_reads_through_awpy3() -> None:
    world = cs2_world(os.environ["DECOY_TEST_NAV"], "de_dust2")
    assert world.meta["areas"] > 1000 and world.source.startswith("CS2 de_dust2 nav mesh")


# ---- the world --------------------------------------------------------------------------------


def test_an_open_edge_gets_a_wall_and_a_shared_edge_none(tmp_path: Path) -> None:
    tris = triangles_of(tmp_path, [square(0, 0, 100, 0), square(100, 0, 100, 0)])
    assert len(faces_on_line(tris, 0, 100)) == 0  # the shared edge is open floor
    outer = faces_on_line(tris, 0, 200 + POLYGON_WALL_PUSH_U)
    assert len(outer) and outer[:, :, 2].max() > 150  # a full wall beyond the open edge


def test_a_floor_of_the_same_level_beyond_a_wall_leaves_the_wall(tmp_path: Path) -> None:
    """Two rooms at one height 80 u apart (a wall between, each nav stopping short of it): a
    full wall stands between them, not an opening."""
    tris = triangles_of(tmp_path, [square(0, 0, 100, 0), square(180, 0, 100, 0)])
    wall = faces_on_line(tris, 0, 100 + POLYGON_WALL_PUSH_U)
    assert len(wall) and wall[:, :, 2].max() > 150


def test_a_shared_edge_between_heights_gets_a_step_face(tmp_path: Path) -> None:
    tris = triangles_of(tmp_path, [square(0, 0, 100, 0), square(100, 0, 100, 40)])
    step = faces_on_line(tris, 0, 100)
    assert len(step) and step[:, :, 2].min() == pytest.approx(0) and step[:, :, 2].max() == 40


def test_a_walkway_over_a_passage_leaves_the_passage_open(tmp_path: Path) -> None:
    """A bridge (z 200) over a passage (z 0): the passage's floor goes on under the bridge, so
    no face hangs from the bridge's edges into the passage, and none stands on the line the
    two floors share seen from above."""
    passage = [square(0, 0, 100, 0), square(100, 0, 100, 0), square(200, 0, 100, 0)]
    bridge = [(100, -200, 200), (200, -200, 200), (200, 300, 200), (100, 300, 200)]
    tris = triangles_of(tmp_path, [*passage, bridge])
    for x in (100, 200, 100 - POLYGON_WALL_PUSH_U, 200 + POLYGON_WALL_PUSH_U):
        faces = faces_on_line(tris, 0, x)
        crossing = (faces[:, :, 1].min(axis=1) < 99) & (faces[:, :, 1].max(axis=1) > 1)
        in_passage = faces[crossing]
        assert in_passage.size == 0 or in_passage[:, :, 2].min() >= 190, x


def test_a_walkway_edge_over_a_passage_hangs_no_face_into_it(tmp_path: Path) -> None:
    """The same with the bridge's edges over the middle of the passage's areas: no face hangs
    from them down to the passage."""
    passage = [square(0, 0, 150, 0), square(150, 0, 150, 0)]
    bridge = [(100, -200, 200), (200, -200, 200), (200, 300, 200), (100, 300, 200)]
    tris = triangles_of(tmp_path, [*passage, bridge])
    vertical = np.abs(np.cross(tris[:, 1] - tris[:, 0], tris[:, 2] - tris[:, 0])[:, 2]) < 1e-6
    faces = tris[vertical]
    inside = np.all((faces[:, :, 0] > 50) & (faces[:, :, 0] < 250), axis=1)
    crossing = (faces[:, :, 1].min(axis=1) < 99) & (faces[:, :, 1].max(axis=1) > 1)
    hanging = faces[inside & crossing]
    assert hanging.size == 0 or hanging[:, :, 2].min() >= 190


def test_a_ledge_is_a_face_down_with_no_wall_above(tmp_path: Path) -> None:
    """A floor at 150 beside a lower one at 0 across a 20 u gap: a face down from the upper
    edge, and nothing above the upper floor there (a drop, not a wall)."""
    tris = triangles_of(tmp_path, [square(0, 0, 100, 150), square(120, 0, 100, 0)])
    face = faces_on_line(tris, 0, 110)
    assert len(face) and face[:, :, 2].max() == pytest.approx(150)


def floors_under(tris: np.ndarray, x: float, y: float) -> list[float]:
    """Heights of the non-vertical triangles under the point (x, y) (Hammer units)."""
    heights = []
    for tri in tris:
        (x0, y0, z0), (x1, y1, z1), (x2, y2, z2) = tri
        det = (y1 - y2) * (x0 - x2) + (x2 - x1) * (y0 - y2)
        if abs(det) < 1e-9:
            continue
        l0 = ((y1 - y2) * (x - x2) + (x2 - x1) * (y - y2)) / det
        l1 = ((y2 - y0) * (x - x2) + (x0 - x2) * (y - y2)) / det
        if min(l0, l1, 1 - l0 - l1) >= -1e-9:
            heights.append(l0 * z0 + l1 * z1 + (1 - l0 - l1) * z2)
    return heights


def test_a_hole_over_a_pit_is_closed_at_its_own_level(tmp_path: Path) -> None:
    """Two floors at 100 u, 16 u apart, over a pit floor at -100 that shows first beyond each
    edge: the hole between the two is closed at 100 (it is one floor a player walks across),
    not a ledge down into the pit."""
    pit = square(-100, -100, 400, -100)
    tris = triangles_of(tmp_path, [square(0, 0, 100, 100), square(116, 0, 100, 100), pit])
    for x in (102.0, 106.0, 110.0, 114.0):
        assert max(floors_under(tris, x, 50.0)) == pytest.approx(100), x


def test_the_holes_where_four_corners_meet_are_closed(tmp_path: Path) -> None:
    """Four floors 10 u apart meeting at their corners: the strips across each gap run past the
    corners, so the hole in the middle is floor too."""
    corners = [square(0, 0, 100, 0), square(110, 0, 100, 0)]
    corners += [square(0, 110, 100, 0), square(110, 110, 100, 0)]
    tris = triangles_of(tmp_path, corners)
    for x, y in ((103.0, 103.0), (105.0, 105.0), (108.0, 102.0)):
        assert floors_under(tris, x, y), (x, y)


def test_a_nav_of_another_map_is_refused(tmp_path: Path) -> None:
    far = nav_document([square(20000, 20000, 100, 0), square(20100, 20000, 100, 0)])
    with pytest.raises(WorldError, match="not a nav mesh of de_dust2"):
        cs2_world(write_nav(tmp_path / "far.json", far), "de_dust2")


# ---- graphs that carry their world -------------------------------------------------------------


def dust2_piece(tmp_path: Path) -> Path:
    """A small piece of de_dust2 as a CS2-style nav: the built-in nav's areas around the
    T spawn, each as a four-corner polygon at its mean height."""
    nav = load_navmesh("de_dust2")
    centre = np.array([-700.0, -900.0])
    near = np.hypot(
        (nav.x_min + nav.x_max) / 2 - centre[0], (nav.y_min + nav.y_max) / 2 - centre[1]
    )
    polygons = []
    for a in np.argsort(near)[:40]:
        z = float(nav.z_at_min[a] + nav.z_at_max[a]) / 2
        polygons.append(
            [
                (float(nav.x_min[a]), float(nav.y_min[a]), z),
                (float(nav.x_max[a]), float(nav.y_min[a]), z),
                (float(nav.x_max[a]), float(nav.y_max[a]), z),
                (float(nav.x_min[a]), float(nav.y_max[a]), z),
            ]
        )
    return write_nav(tmp_path / "piece.json", nav_document(polygons))


def piece_seed(path: Path) -> list[float]:
    nav = read_nav(path)
    areas = (nav.corners[:, 2, 0] - nav.corners[:, 0, 0]) * (
        nav.corners[:, 2, 1] - nav.corners[:, 0, 1]
    )
    biggest = nav.polygon(int(np.argmax(areas)))
    return (biggest.mean(axis=0) * HAMMER_TO_M).tolist()


def test_a_graph_built_on_a_cs2_world_carries_it_and_replays_on_it(tmp_path: Path) -> None:
    path = dust2_piece(tmp_path)
    world = cs2_world(path, "de_dust2")
    graph, _ = build_graph(world, "de_dust2", np.array([piece_seed(path)]), LatticeParams())
    graph.save(tmp_path / "g.npz")
    loaded = WaypointGraph.load(tmp_path / "g.npz")
    carried = graph_world(loaded)
    assert np.array_equal(carried.triangles, world.triangles)
    assert "CS2 de_dust2 nav mesh" in carried.source
    loaded.world_triangles[0, 0, 0] += 1.0  # a graph whose world was changed after the build
    with pytest.raises(GraphError, match="does not match its own fingerprint"):
        graph_world(loaded)


def test_build_waypoints_nav_writes_a_graph_with_its_world(tmp_path: Path) -> None:
    path = dust2_piece(tmp_path)
    document = json.loads(path.read_text())
    document["areas"]["1"]["ladders_above"] = [7]  # a ladder id: the form holds no position
    write_nav(path, document)
    seed = ",".join(f"{v:g}" for v in piece_seed(path))
    out = tmp_path / "cs2.npz"
    result = runner.invoke(
        app,
        ["build-waypoints", "--nav", str(path), "--seed", seed, "--out", str(out), "--no-plot"],
        env={"COLUMNS": "200"},
    )
    assert result.exit_code == 0, result.output
    assert "CS2 de_dust2 nav mesh" in result.output
    assert "1 ladder links but no ladder positions" in result.output
    graph = WaypointGraph.load(out)
    assert graph.world_triangles is not None
    climbs = len(world_climbs(cs2_world(path, "de_dust2")))
    assert f"{graph.meta['climbs_joined']} of the nav's {climbs} joined" in result.output


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["--nav", "missing.json"], "missing.json"),
        (["--nav", "x.json", "--mesh", "y.obj"], "give one"),
    ],
)
def test_build_waypoints_nav_refuses_bad_requests(
    tmp_path: Path, args: list[str], message: str
) -> None:
    result = runner.invoke(app, ["build-waypoints", *args, "--out", str(tmp_path / "g.npz")])
    assert result.exit_code == 1
    assert result.output.startswith("error:") and message in result.output
    assert len(result.output.strip().splitlines()) == 1


@pytest.mark.skipif(not CS2_NAV.is_file(), reason=f"{CS2_NAV} is absent (../shared/data)")
def test_the_cs2_dust2_nav_is_de_dust2_s_and_no_other_map_s() -> None:
    """Its areas lie on de_dust2's built-in nav; another map refuses it before any building
    (the world itself: `test_the_shipped_cs2_graph_is_current`)."""
    nav = read_nav(CS2_NAV)
    assert nav.num_areas == 2248 and nav.version == 35
    assert on_map_share(nav, "de_dust2") > SAME_MAP_SHARE
    with pytest.raises(WorldError, match="not a nav mesh of de_nuke"):
        cs2_world(CS2_NAV, "de_nuke")


# ---- the shipped CS2 world and the choice of world ----------------------------------------------


@pytest.mark.skipif(not CS2_NAV.is_file(), reason=f"{CS2_NAV} is absent (../shared/data)")
def test_the_shipped_cs2_graph_is_current(tmp_path: Path) -> None:
    """Rebuilding the CS2 de_dust2 graph from the nav file gives the shipped bytes (the command
    in assets/de_dust2/ATTRIBUTION.md), run whenever its inputs changed since its stamp."""
    assert_rebuilt_when_inputs_changed("de_dust2", CS2_GRAPH_FILE, tmp_path)


def test_the_shipped_cs2_graph_carries_a_cs2_world() -> None:
    graph = builtin_graph("de_dust2", "cs2")
    world = graph_world(graph)
    assert world.source.startswith("CS2 de_dust2 nav mesh")
    low, high = world.bounds
    assert 70 < high[0] - low[0] < 90 and 75 < high[1] - low[1] < 90  # de_dust2's size (m)
    assert graph.world_triangles is not None and set(graph.regions) == set(REGIONS)
    assert all(len(nodes) > 50 for nodes in graph.regions.values())


def test_a_map_without_a_cs2_world_says_so() -> None:
    with pytest.raises(GraphError, match="ships no CS2 world of de_nuke"):
        builtin_graph("de_nuke", "cs2")


def test_evaluate_names_the_world_it_replays_on(tmp_path: Path) -> None:
    from decoy_cli.esta import read_match
    from decoy_cli.esta.awpy.writer import write_awpy2_zip
    from decoy_cli.synth.sample import SAMPLE_DIR

    sample = read_match(sorted(SAMPLE_DIR.glob("*.json*"))[0])
    zipped = write_awpy2_zip(sample, tmp_path / "m.zip")
    out = tmp_path / "run"
    args = ["evaluate", str(zipped), "--sample", "1", "--no-combat", "--no-bomb", "--world", "cs2"]
    result = runner.invoke(
        app, [*args, "--workers", "1", "--no-view", "--no-figures", "--out", str(out)]
    )
    assert result.exit_code == 0, result.output
    summary = json.loads((out / "summary.json").read_text())
    assert summary["world"].startswith("CS2 de_dust2 nav mesh")
    assert "--world cs2" in summary["command"]
    assert "| world | CS2 de_dust2 nav mesh" in (out / "report.md").read_text()


def test_snap_snaps_to_the_world_asked_for(tmp_path: Path) -> None:
    from decoy_cli.esta import read_match
    from decoy_cli.esta.awpy.writer import write_awpy2_zip
    from decoy_cli.synth.sample import SAMPLE_DIR

    zipped = write_awpy2_zip(read_match(sorted(SAMPLE_DIR.glob("*.json*"))[0]), tmp_path / "m.zip")
    for world, expected in ((["--world", "cs2"], "world: CS2 de_dust2"), ([], "world: built-in")):
        result = runner.invoke(app, ["snap", f"{zipped}:1", *world], env={"COLUMNS": "200"})
        assert result.exit_code == 0, result.output
        assert expected in result.output
