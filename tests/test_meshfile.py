"""Reading and writing user meshes (`.obj`, awpy `.tri`): formats, options, errors, real dust2."""

from __future__ import annotations

import hashlib
import struct
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays
from worlds import write_awmh

from decoy_cli.csgo import HAMMER_TO_M
from decoy_cli.errors import OutputError, WorldError
from decoy_cli.world.meshfile import (
    UP_AXES,
    check_extent,
    read_mesh,
    write_obj,
    write_tri,
)
from decoy_cli.world.world import World

DATA = Path(__file__).resolve().parents[1].parent / "shared" / "data"
DUST2_TRI = DATA / "meshes" / "de_dust2_moh-maps.tri"
DUST2_SHA256 = "16402a7e6fb64fb8a0b380e4f3864752fa229aaf61e53d9fd71a056e9f23486d"

# Unit cube: vertex k has coordinates given by its bits (x = bit 0, y = bit 1, z = bit 2).
CUBE_VERTICES = [(k & 1, (k >> 1) & 1, (k >> 2) & 1) for k in range(8)]
CUBE_QUADS = [  # 0-based, outward counter-clockwise
    (0, 2, 3, 1),  # bottom z=0
    (4, 5, 7, 6),  # top z=1
    (0, 1, 5, 4),  # south y=0
    (2, 6, 7, 3),  # north y=1
    (0, 4, 6, 2),  # west x=0
    (1, 3, 7, 5),  # east x=1
]
CUBE_AREA = 6.0


def _cube_obj(ref: str = "{i}", *, negative: bool = False, split_quads: bool = False) -> str:
    """OBJ text of the unit cube, face references formatted by `ref` (1-based index i)."""
    lines = ["# unit cube", "mtllib cube.mtl", "o cube", "g box"]
    lines += [f"v {x} {y} {z}" for x, y, z in CUBE_VERTICES]
    lines += ["vt 0 0", "vt 1 1", "vn 0 0 1", "usemtl grey", "s off"]
    faces = CUBE_QUADS
    if split_quads:
        faces = [t for a, b, c, d in CUBE_QUADS for t in ((a, b, c), (a, c, d))]
    for face in faces:
        indices = [i - 8 if negative else i + 1 for i in face]
        lines.append("f " + " ".join(ref.format(i=i) for i in indices))
    return "\n".join(lines) + "\n"


def _write(path: Path, text: str) -> Path:
    path.write_text(text)
    return path


def _area(triangles: np.ndarray) -> float:
    edge1 = triangles[:, 1] - triangles[:, 0]
    edge2 = triangles[:, 2] - triangles[:, 0]
    return float(np.linalg.norm(np.cross(edge1, edge2), axis=1).sum() / 2)


def _normals(triangles: np.ndarray) -> np.ndarray:
    return np.cross(triangles[:, 1] - triangles[:, 0], triangles[:, 2] - triangles[:, 0])


def _two_triangles_tri(path: Path, values: np.ndarray | None = None) -> Path:
    tri = np.array(
        [[[0, 0, 0], [100, 0, 0], [0, 100, 0]], [[0, 0, 10], [0, 50, 10], [50, 0, 10]]],
        dtype="<f4",
    )
    path.write_bytes((tri if values is None else values).astype("<f4").tobytes())
    return path


# ---- OBJ -------------------------------------------------------------------------------------


@pytest.mark.parametrize("ref", ["{i}", "{i}/{i}", "{i}//1", "{i}/1/1"])
@pytest.mark.parametrize("negative", [False, True])
def test_obj_cube_in_every_face_format(tmp_path: Path, ref: str, negative: bool) -> None:
    path = _write(tmp_path / "cube.obj", _cube_obj(ref, negative=negative))
    world = read_mesh(path, units="m")
    expected = np.array(CUBE_VERTICES, dtype=float)[
        [[a, b, c] for q in CUBE_QUADS for a, b, c in ((q[0], q[1], q[2]), (q[0], q[2], q[3]))]
    ]
    np.testing.assert_array_equal(world.triangles, expected)
    assert world.num_triangles == 12
    assert _area(world.triangles) == pytest.approx(CUBE_AREA)
    # fan triangulation keeps the winding: every normal points out of the cube
    centres = world.triangles.mean(axis=1) - 0.5
    assert np.all(np.einsum("ij,ij->i", _normals(world.triangles), centres) > 0)


def test_obj_quads_equal_their_triangles(tmp_path: Path) -> None:
    quads = read_mesh(_write(tmp_path / "q.obj", _cube_obj()), units="m")
    tris = read_mesh(_write(tmp_path / "t.obj", _cube_obj(split_quads=True)), units="m")
    np.testing.assert_array_equal(quads.triangles, tris.triangles)


def test_obj_polygon_is_fan_triangulated(tmp_path: Path) -> None:
    ring = [(np.cos(a), np.sin(a), 0.0) for a in np.linspace(0, 2 * np.pi, 6)[:-1]]
    text = "".join(f"v {x} {y} {z}\n" for x, y, z in ring) + "f 1 2 3 4 5\n"
    world = read_mesh(_write(tmp_path / "pentagon.obj", text), units="m")
    ring_array = np.array(ring)
    np.testing.assert_array_equal(world.triangles, ring_array[[[0, 1, 2], [0, 2, 3], [0, 3, 4]]])


def test_obj_negative_indices_are_relative_to_vertices_so_far(tmp_path: Path) -> None:
    text = (
        "v 0 0 0\nv 1 0 0\nv 0 1 0\nf -3 -2 -1\nv 5 0 0\nv 6 0 0\nv 5 1 0\nf -3 -2 -1\nf 1 5 -1\n"
    )
    world = read_mesh(_write(tmp_path / "rel.obj", text), units="m")
    np.testing.assert_array_equal(world.triangles[0], [[0, 0, 0], [1, 0, 0], [0, 1, 0]])
    np.testing.assert_array_equal(world.triangles[1], [[5, 0, 0], [6, 0, 0], [5, 1, 0]])
    np.testing.assert_array_equal(world.triangles[2], [[0, 0, 0], [6, 0, 0], [5, 1, 0]])


def test_obj_ignores_other_statements_and_extra_vertex_values(tmp_path: Path) -> None:
    text = (
        "# comment f 9 9 9\r\n"
        "mtllib a.mtl\r\n"
        "o thing\r\n"
        "v 1 2 3 1.0\r\n"  # w
        "v\t4 5 6 0.1 0.2 0.3\r\n"  # vertex colour, tab separated
        "  v 7 8 9\r\n"  # leading blanks
        "vt 0.5 0.5\r\n"
        "vn 0 0 1\r\n"
        "vp 0.1\r\n"
        "g group\r\n"
        "usemtl stone\r\n"
        "s 1\r\n"
        "l 1 2\r\n"
        "p 3\r\n"
        "\r\n"
        "f 1/1/1 2/1/1 3/1/1\r\n"
    )
    world = read_mesh(_write(tmp_path / "misc.obj", text), units="m")
    np.testing.assert_array_equal(world.triangles, [[[1, 2, 3], [4, 5, 6], [7, 8, 9]]])
    assert world.meta["format"] == "obj"


def test_obj_with_byte_order_mark_keeps_its_first_vertex(tmp_path: Path) -> None:
    path = tmp_path / "bom.obj"
    path.write_bytes(b"\xef\xbb\xbfv 1 2 3\nv 4 5 6\nv 7 8 9\nf 1 2 3\n")
    world = read_mesh(path, units="m")
    np.testing.assert_array_equal(world.triangles, [[[1, 2, 3], [4, 5, 6], [7, 8, 9]]])


# ---- .tri ------------------------------------------------------------------------------------


def test_tri_two_triangles_in_hammer_units(tmp_path: Path) -> None:
    path = _two_triangles_tri(tmp_path / "two.tri")
    world = read_mesh(path)
    assert world.num_triangles == 2
    np.testing.assert_allclose(world.triangles[0, 1], [100 * HAMMER_TO_M, 0, 0])
    np.testing.assert_allclose(world.triangles[1, 1], [0, 50 * HAMMER_TO_M, 10 * HAMMER_TO_M])
    assert world.name == "two"
    assert world.source == str(path)
    assert world.meta["format"] == "tri"
    assert world.meta["file_sha256"] == hashlib.sha256(path.read_bytes()).hexdigest()


def test_extension_is_case_insensitive(tmp_path: Path) -> None:
    world = read_mesh(_two_triangles_tri(tmp_path / "TWO.TRI"), units="m")
    assert world.triangles[0, 1, 0] == 100


# ---- .mesh (awpy 3) -------------------------------------------------------------------------


def _awmh(version: int, vertices: int, triangles: int, body: bytes = b"") -> bytes:
    return struct.pack("<4s3I", b"AWMH", version, vertices, triangles) + body


def test_awpy3_mesh_reads_the_triangles_a_tri_holds(tmp_path: Path) -> None:
    tri = read_mesh(_two_triangles_tri(tmp_path / "two.tri"))
    write_awmh(tri, tmp_path / "two.mesh")
    mesh = read_mesh(tmp_path / "two.mesh")
    np.testing.assert_allclose(mesh.triangles, tri.triangles, rtol=1e-6, atol=1e-9)
    assert mesh.meta["format"] == "mesh" and mesh.name == "two"
    (tmp_path / "tail.mesh").write_bytes((tmp_path / "two.mesh").read_bytes() + b"more")
    np.testing.assert_array_equal(read_mesh(tmp_path / "tail.mesh").triangles, mesh.triangles)


def test_real_dust2_as_an_awpy3_mesh(dust2_tri: Path, tmp_path: Path) -> None:
    world = read_mesh(dust2_tri)
    write_awmh(world, tmp_path / "de_dust2.mesh")
    mesh = read_mesh(tmp_path / "de_dust2.mesh")
    assert mesh.num_triangles == world.num_triangles
    np.testing.assert_allclose(mesh.triangles, world.triangles, rtol=0, atol=1e-4)


AWMH_ERRORS = [
    (b"OBJ " + bytes(12), "not an awpy .mesh file"),
    (b"AWM", "not an awpy .mesh file"),
    (_awmh(2, 3, 1, bytes(48)), "awpy .mesh version 2; this decoy reads version 1"),
    (_awmh(1, 3, 1, bytes(47)), "truncated: its header promises 3 vertices and 1 triangles"),
    (_awmh(1, 2**32 - 1, 2**32 - 1), "promises 4,294,967,295 vertices"),
    (_awmh(1, 3, 0, bytes(36)), "the mesh has no triangles"),
    (_awmh(1, 3, 1, bytes(36) + struct.pack("<3I", 0, 1, 3)), "refers to vertex 3, but 3"),
    (
        _awmh(1, 3, 1, struct.pack("<9f3I", 0, 0, 0, 1, 0, 0, float("nan"), 1, 0, 0, 1, 2)),
        "triangle 0 has a NaN or infinite coordinate",
    ),
]


@pytest.mark.parametrize(("content", "fragment"), AWMH_ERRORS)
def test_a_bad_awpy3_mesh_is_one_line_naming_the_file(
    tmp_path: Path, content: bytes, fragment: str
) -> None:
    path = tmp_path / "bad.mesh"
    path.write_bytes(content)
    with pytest.raises(WorldError) as caught:
        read_mesh(path)
    assert str(path) in str(caught.value) and fragment in str(caught.value)
    assert "\n" not in str(caught.value)


# ---- options ---------------------------------------------------------------------------------


def test_units_and_scale(tmp_path: Path) -> None:
    path = _two_triangles_tri(tmp_path / "two.tri")
    raw = np.fromfile(path, "<f4").reshape(-1, 3, 3).astype(float)
    np.testing.assert_allclose(read_mesh(path, units="m").triangles, raw)
    np.testing.assert_allclose(read_mesh(path, units="hammer").triangles, raw * HAMMER_TO_M)
    np.testing.assert_allclose(read_mesh(path).triangles, raw * HAMMER_TO_M)
    # scale replaces the units factor: it is the metres per file unit, whatever `units` says
    for units in ("m", "hammer"):
        inches = read_mesh(path, units=units, scale=0.0254)
        np.testing.assert_allclose(inches.triangles, raw * 0.0254)
        assert inches.meta["metres_per_unit"] == 0.0254
        assert inches.meta["units"] is None
    assert read_mesh(path).meta["units"] == "hammer"
    assert read_mesh(path, scale=2).meta["metres_per_unit"] == 2.0
    assert read_mesh(path, scale=np.float32(0.5)).meta["metres_per_unit"] == 0.5


def test_up_axis_y_maps_x_y_z_to_x_minus_z_y(tmp_path: Path) -> None:
    text = "v 1 2 3\nv 4 5 6\nv 7 8 10\nf 1 2 3\n"
    world = read_mesh(_write(tmp_path / "yup.obj", text), units="m", up_axis="y")
    np.testing.assert_array_equal(world.triangles, [[[1, -3, 2], [4, -6, 5], [7, -10, 8]]])
    assert world.meta["up_axis"] == "y"
    for spelling in ("+y", "Y", " y "):
        same = read_mesh(tmp_path / "yup.obj", units="m", up_axis=spelling)
        np.testing.assert_array_equal(same.triangles, world.triangles)


@pytest.mark.parametrize("axis", sorted(UP_AXES))
def test_every_up_axis_is_a_proper_rotation_onto_z(tmp_path: Path, axis: str) -> None:
    rotation = UP_AXES[axis]
    up = np.zeros(3)
    up["xyz".index(axis[-1])] = -1.0 if axis.startswith("-") else 1.0
    np.testing.assert_array_equal(rotation @ up, [0, 0, 1])
    np.testing.assert_allclose(rotation @ rotation.T, np.eye(3))
    assert np.linalg.det(rotation) == pytest.approx(1.0)
    # a mesh written with `axis` up reads back z-up, with normals still pointing outward
    cube = read_mesh(_write(tmp_path / "c.obj", _cube_obj()), units="m")
    tilted = World(cube.triangles @ np.linalg.inv(rotation).T, name="c", source="c")
    write_obj(tilted, tmp_path / "tilted.obj", units="m")
    back = read_mesh(tmp_path / "tilted.obj", units="m", up_axis=axis)
    np.testing.assert_allclose(back.triangles, cube.triangles, atol=1e-12)


def test_scale_then_up_axis_then_offset_in_metres(tmp_path: Path) -> None:
    path = _write(tmp_path / "p.obj", "v 1 2 3\nv 1 2 4\nv 2 2 3\nf 1 2 3\n")
    world = read_mesh(path, scale=2.0, up_axis="y", offset=(10, 20, 30))
    # (1, 2, 3) -> scaled (2, 4, 6) -> y-up (2, -6, 4) -> offset (12, 14, 34)
    np.testing.assert_allclose(world.triangles[0, 0], [12, 14, 34])
    np.testing.assert_allclose(world.triangles[0, 1], [12, 12, 34])
    assert world.meta["offset_m"] == [10.0, 20.0, 30.0]


def test_name_defaults_to_file_stem(tmp_path: Path) -> None:
    path = _two_triangles_tri(tmp_path / "my_map.tri")
    assert read_mesh(path).name == "my_map"
    assert read_mesh(path, name="dust").name == "dust"


# ---- errors ----------------------------------------------------------------------------------


def _nan_tri(path: Path) -> Path:
    values = np.zeros((2, 3, 3))
    values[1, 2, 0] = np.nan
    return _two_triangles_tri(path, values)


ERROR_FILES = [
    # (file name, content: bytes, str, None = nothing, "dir" = a directory, message fragment)
    ("missing.obj", None, "no such mesh file"),
    ("folder.obj", "dir", "is a directory"),
    ("mesh.stl", "solid x\n", "unknown mesh format '.stl'"),
    ("mesh", "v 0 0 0\n", "no file extension"),
    ("short.tri", b"\0" * 40, "40 bytes is not a multiple of 36"),
    ("empty.tri", b"", "the file is empty"),
    ("empty.obj", "", "the file is empty"),
    ("inf.obj", "v 0 0 0\nv 1 0 0\nv 0 1e400 0\nf 1 2 3\n", "line 3: vertex has a NaN"),
    ("nan.obj", "v nan 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n", "line 1: vertex has a NaN"),
    ("far.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 4\n", "line 4: face refers to vertex 4, but 3"),
    ("rel.obj", "v 0 0 0\nv 1 0 0\nf -1 -2 -3\nv 0 1 0\n", "face refers to vertex -3, but 2"),
    ("zero.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 0 1 2\n", "face refers to vertex 0"),
    ("noface.obj", "# only vertices\nv 0 0 0\nv 1 0 0\nv 0 1 0\n", "has no faces"),
    ("blank.obj", "\n \n", "has no faces"),
    ("word.obj", "v 0 0 0\nv 1 zero 0\nv 0 1 0\nf 1 2 3\n", "line 2: 'zero' is not a valid"),
    ("badref.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\n\nf 1 2 x/1\n", "line 5: 'x' is not a valid"),
    ("hugeref.obj", "v 0 0 0\nf 1 1 99999999999999999999\n", "is not a valid number"),
    ("twoface.obj", "v 0 0 0\nv 1 0 0\nf 1 2\n", "line 3: a face needs at least 3"),
    ("flat.obj", "v 0 0\nf 1 1 1\n", "line 1: a vertex needs x, y and z"),
]


@pytest.mark.parametrize(("name", "content", "fragment"), ERROR_FILES)
def test_bad_files_raise_one_line_naming_the_file(
    tmp_path: Path, name: str, content: bytes | str | None, fragment: str
) -> None:
    path = tmp_path / name
    if content == "dir":
        path.mkdir()
    elif isinstance(content, bytes):
        path.write_bytes(content)
    elif isinstance(content, str):
        path.write_text(content)
    with pytest.raises(WorldError) as caught:
        read_mesh(path)
    message = str(caught.value)
    assert str(path) in message
    assert fragment in message
    assert "\n" not in message


def test_nan_in_tri_names_the_triangle(tmp_path: Path) -> None:
    path = _nan_tri(tmp_path / "nan.tri")
    with pytest.raises(WorldError, match=r"nan\.tri: triangle 1 has a NaN or infinite"):
        read_mesh(path)


def test_overflow_after_scaling_is_an_error(tmp_path: Path) -> None:
    path = _write(tmp_path / "big.obj", "v 1e300 0 0\nv 0 1 0\nv 0 0 1\nf 1 2 3\n")
    with pytest.raises(WorldError, match="overflow"):
        read_mesh(path, scale=1e10)


@pytest.mark.parametrize(
    ("options", "fragment"),
    [
        ({"up_axis": "w"}, "unknown up axis 'w'"),
        ({"up_axis": "xy"}, "unknown up axis"),
        ({"units": "inch"}, "unknown units 'inch'"),
        ({"scale": 0}, "scale must be a positive finite number"),
        ({"scale": -0.01905}, "scale must be a positive finite number"),
        ({"scale": float("nan")}, "scale must be a positive finite number"),
        ({"scale": float("inf")}, "scale must be a positive finite number"),
        ({"scale": "2"}, "scale must be a number"),
        ({"offset": (1, 2)}, "offset must be three finite numbers"),
        ({"offset": (1, 2, float("nan"))}, "offset must be three finite numbers"),
        ({"offset": ("a", 2, 3)}, "offset must be three numbers"),
    ],
)
def test_bad_options_raise(tmp_path: Path, options: dict, fragment: str) -> None:
    path = _two_triangles_tri(tmp_path / "two.tri")
    with pytest.raises(WorldError) as caught:
        read_mesh(path, **options)
    assert fragment in str(caught.value)
    assert str(path) in str(caught.value)


# ---- plausibility ----------------------------------------------------------------------------


def _box_world(dx: float, dy: float, dz: float, **meta: object) -> World:
    corners = np.array([[0, 0, 0], [dx, 0, 0], [0, dy, dz]], dtype=float)
    return World(corners[None], name="box", source="box.obj", meta=dict(meta))


def test_check_extent_accepts_a_map_sized_mesh() -> None:
    check_extent(_box_world(100, 100, 20, units="hammer"))


@pytest.mark.parametrize(
    ("world", "fragment"),
    [
        (_box_world(1.9, 2.0, 0.4, units="hammer"), "too small for a map; try --units m"),
        (_box_world(1.9, 2.0, 0.4, units="m"), "too small for a map; try --scale"),
        (_box_world(1.9, 2.0, 0.4), "try --units m or --scale"),
        (_box_world(5000, 5300, 1000, units="m"), "too large for a map; try --units hammer"),
        (_box_world(5000, 5300, 1000, units="hammer"), "too large for a map; try --scale"),
        (_box_world(100, 19, 99, units="hammer"), "taller than one of its horizontal sides"),
    ],
)
def test_check_extent_hints_at_the_fix(world: World, fragment: str) -> None:
    with pytest.raises(WorldError) as caught:
        check_extent(world)
    assert fragment in str(caught.value)
    assert str(caught.value).startswith("box.obj: ")


def test_check_extent_hints_up_axis_for_a_y_up_mesh(tmp_path: Path) -> None:
    # a 100 m x 80 m floor and a 10 m wall, written Y-up (as exporters do) and read as Z-up
    text = "v 0 0 0\nv 100 0 0\nv 0 0 -80\nv 0 10 0\nf 1 2 3\nf 1 2 4\n"
    path = _write(tmp_path / "yup.obj", text)
    with pytest.raises(WorldError, match="try --up-axis y"):
        check_extent(read_mesh(path, units="m"))
    check_extent(read_mesh(path, units="m", up_axis="y"))


# ---- writers ---------------------------------------------------------------------------------


def test_obj_round_trip_in_metres_is_exact(tmp_path: Path) -> None:
    cube = read_mesh(_write(tmp_path / "c.obj", _cube_obj("{i}/1/1", negative=True)), units="m")
    moved = World(cube.triangles * 1.37 + [0.1, -2.3, 1e-9], name="cube", source="mem")
    write_obj(moved, tmp_path / "out.obj", units="m")
    back = read_mesh(tmp_path / "out.obj", units="m")
    np.testing.assert_array_equal(back.triangles, moved.triangles)
    text = (tmp_path / "out.obj").read_text()
    assert text.count("\nv ") == 8  # shared vertices
    assert text.count("\nf ") == 12


def test_obj_and_tri_default_to_hammer_units_like_the_reader(tmp_path: Path) -> None:
    world = read_mesh(_two_triangles_tri(tmp_path / "two.tri"))
    write_obj(world, tmp_path / "two.obj")
    write_tri(world, tmp_path / "again.tri")
    np.testing.assert_allclose(read_mesh(tmp_path / "two.obj").triangles, world.triangles)
    assert (tmp_path / "again.tri").read_bytes() == (tmp_path / "two.tri").read_bytes()
    assert "100.0" in (tmp_path / "two.obj").read_text()


def test_tri_round_trip_in_metres(tmp_path: Path) -> None:
    world = _box_world(3.25, 4.5, 1.0)
    write_tri(world, tmp_path / "m.tri", units="m")
    assert (tmp_path / "m.tri").stat().st_size == 36
    np.testing.assert_array_equal(
        read_mesh(tmp_path / "m.tri", units="m").triangles, world.triangles
    )


@settings(max_examples=25, deadline=None)
@given(
    arrays(
        np.float64,
        st.tuples(st.integers(1, 6), st.just(3), st.just(3)),
        elements=st.floats(-5000, 5000, allow_nan=False, allow_subnormal=False),
    )
)
def test_random_soups_round_trip(tmp_path_factory: pytest.TempPathFactory, tri: np.ndarray) -> None:
    folder = tmp_path_factory.mktemp("soup")
    world = World(tri, name="soup", source="mem")
    write_obj(world, folder / "s.obj", units="m")
    write_tri(world, folder / "s.tri", units="m")
    np.testing.assert_array_equal(read_mesh(folder / "s.obj", units="m").triangles, tri)
    np.testing.assert_array_equal(
        read_mesh(folder / "s.tri", units="m").triangles, tri.astype(np.float32)
    )


def test_writers_replace_atomically_and_leave_no_temp_files(tmp_path: Path) -> None:
    world = _box_world(1, 2, 3)
    target = tmp_path / "sub" / "out.obj"
    write_obj(world, target, units="m")  # creates the missing folder
    write_obj(_box_world(4, 5, 6), target, units="m")  # replaces the file
    assert read_mesh(target, units="m").bounds[1].tolist() == [4, 5, 6]
    write_tri(world, tmp_path / "sub" / "out.tri")
    assert sorted(p.name for p in target.parent.iterdir()) == ["out.obj", "out.tri"]
    assert target.stat().st_mode & 0o777 == 0o644


@pytest.mark.parametrize("writer", [write_obj, write_tri])
def test_writers_refuse_a_directory(tmp_path: Path, writer) -> None:
    with pytest.raises(OutputError, match="is a directory"):
        writer(_box_world(1, 2, 3), tmp_path)
    with pytest.raises(WorldError, match="unknown units"):
        writer(_box_world(1, 2, 3), tmp_path / "x.obj", units="feet")


# ---- the real de_dust2 brush mesh ------------------------------------------------------------


@pytest.fixture(scope="module")
def dust2_tri() -> Path:
    if not DUST2_TRI.is_file():
        pytest.skip(f"real mesh not available: {DUST2_TRI} (shared data lives next to the repo)")
    return DUST2_TRI


def test_real_dust2_tri(dust2_tri: Path) -> None:
    world = read_mesh(dust2_tri)
    assert world.num_triangles == 57_483
    low, high = world.bounds
    # the README's Hammer box, rounded to 0.1 u
    atol = 0.051 * HAMMER_TO_M
    np.testing.assert_allclose(low, np.array([-3168, -1344, -320]) * HAMMER_TO_M, atol=atol)
    np.testing.assert_allclose(high, np.array([2213.6, 3868.5, 698]) * HAMMER_TO_M, atol=atol)
    assert world.meta["file_sha256"] == DUST2_SHA256
    assert hashlib.sha256(dust2_tri.read_bytes()).hexdigest() == DUST2_SHA256
    check_extent(world)


def test_real_dust2_round_trips_through_both_writers(dust2_tri: Path, tmp_path: Path) -> None:
    world = read_mesh(dust2_tri)
    write_tri(world, tmp_path / "d2.tri")
    assert hashlib.sha256((tmp_path / "d2.tri").read_bytes()).hexdigest() == DUST2_SHA256
    write_obj(world, tmp_path / "d2.obj")
    back = read_mesh(tmp_path / "d2.obj")
    assert back.num_triangles == 57_483
    np.testing.assert_allclose(back.triangles, world.triangles, rtol=0, atol=1e-12)
