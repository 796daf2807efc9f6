"""User map meshes: read a Wavefront `.obj`, an awpy-style `.tri` or an awpy 3 `.mesh` into a
`World`, and write the first two.

Formats:

* `.tri` (awpy): raw little-endian float32, 9 values per triangle (three x, y, z vertices), no
  header; the file size is a multiple of 36 bytes.
* `.mesh` (awpy 3's collision meshes, `awpy get`): little-endian, `AWMH`, then version (1),
  vertex count and triangle count as uint32, the vertices (3 float32 each), the triangles (3
  uint32 vertex indices each); bytes after them are ignored, as awpy ignores them.
* `.obj` (Wavefront): `v x y z [w | r g b]` vertices and `f` faces of 3 or more vertex
  references (`i`, `i/t`, `i//n`, `i/t/n`; negative = relative to the vertices defined so far),
  polygons fan-triangulated. Every other statement (vn, vt, o, g, s, usemtl, mtllib, l, p,
  comments) is ignored. Line continuation with a trailing backslash is not supported.

Reading converts to the project frame once, in this order:

1. units: each file coordinate is multiplied by the metres per file unit, which is `scale` when
   given (e.g. 0.0254 for inches, 0.01 for centimetres) and otherwise the factor of `units`
   ("hammer": 0.01905, "m": 1). `scale` *replaces* the units factor, it does not multiply it:
   one number says what one file unit is in metres.
2. up axis: the file's up axis is turned onto +z by a proper rotation (right-handed stays
   right-handed); e.g. "y" (most OBJ exporters) maps (x, y, z) to (x, -z, y).
3. offset: added last, in metres.

Every bad input raises `WorldError` with one line that names the file. `check_extent` catches
the usual wrong-option mistakes (Hammer read as metres, metres read as Hammer, Y-up read as Z-up)
by the mesh's size and shape.

The OBJ parser is a small one of our own: one `str.split` per line, then numpy for the number
conversion, index resolution and triangulation: a median 80-93 ms for a 57k-triangle file on a
2-core machine. trimesh 5.2.0 (`load(force="mesh", process=False)`) took medians of 72-108 ms on
the same files: no speed to gain, and it would add a dependency whose exceptions and vertex
handling we would have to wrap, and it cannot say which line of the file is wrong.
"""

from __future__ import annotations

import hashlib
import numbers
import os
import struct
from collections.abc import Callable, Sequence
from pathlib import Path

import numpy as np

from decoy_cli.csgo import HAMMER_TO_M
from decoy_cli.errors import WorldError
from decoy_cli.files import write_atomic
from decoy_cli.reading import open_regular
from decoy_cli.world.world import World

UNITS: dict[str, float] = {"hammer": HAMMER_TO_M, "m": 1.0}
"""Metres per file unit for each named unit."""

UP_AXES: dict[str, np.ndarray] = {
    "z": np.eye(3),
    "-z": np.array([[1.0, 0, 0], [0, -1, 0], [0, 0, -1]]),  # half turn about x
    "y": np.array([[1.0, 0, 0], [0, 0, -1], [0, 1, 0]]),  # (x, y, z) -> (x, -z, y)
    "-y": np.array([[1.0, 0, 0], [0, 0, 1], [0, -1, 0]]),  # (x, y, z) -> (x, z, -y)
    "x": np.array([[0, 0, -1.0], [0, 1, 0], [1, 0, 0]]),  # (x, y, z) -> (-z, y, x)
    "-x": np.array([[0, 0, 1.0], [0, 1, 0], [-1, 0, 0]]),  # (x, y, z) -> (z, y, -x)
}
"""Rotation that turns each possible file up axis onto +z (all with determinant +1)."""

FORMATS = (".obj", ".tri", ".mesh")

MIN_EXTENT_M = 5.0
MAX_EXTENT_M = 2000.0
"""Plausible horizontal size of a CS:GO map (de_dust2 is about 100 m across)."""

_TRI_BYTES = 36
_AWMH = b"AWMH"
_AWMH_VERSION = 1
_AWMH_HEADER = struct.Struct("<4s3I")


def read_mesh(
    path: str | os.PathLike[str],
    *,
    units: str = "hammer",
    scale: float | None = None,
    up_axis: str = "z",
    offset: Sequence[float] = (0.0, 0.0, 0.0),
    name: str | None = None,
) -> World:
    """Read a `.obj`, `.tri` or `.mesh` into a `World` in metres (see the module docstring)."""
    path = Path(path)
    factor = _metres_per_unit(path, units, scale)
    axis, rotation = _up_rotation(path, up_axis)
    shift = _offset(path, offset)
    data = _read_bytes(path)
    suffix = path.suffix.lower()
    parse = {".tri": _parse_tri, ".mesh": _parse_awmh}.get(suffix, _parse_obj)
    raw = parse(data, path)
    with np.errstate(over="ignore", invalid="ignore"):
        triangles = (raw.astype(np.float64) * factor) @ rotation.T + shift
    if not np.all(np.isfinite(triangles)):
        raise WorldError(f"{path}: coordinates overflow after scaling by {factor:g}")
    meta: dict[str, object] = {
        "format": suffix[1:],
        "units": units if scale is None else None,
        "metres_per_unit": factor,
        "up_axis": axis,
        "offset_m": [float(v) for v in shift],
        "file_sha256": hashlib.sha256(data).hexdigest(),
    }
    return World(triangles, name=name or path.stem, source=str(path), meta=meta)


def check_extent(world: World) -> None:
    """Raise `WorldError` with a hint when the world's size or shape does not fit a CS:GO map.

    A real map is tens to hundreds of metres across and much less tall than wide or deep; a mesh
    read with the wrong units is 52 times too small or too large, and a Y-up mesh read as Z-up
    stands on its side (its height becomes a horizontal side and vice versa).
    """
    low, high = world.bounds
    dx, dy, dz = (high - low).tolist()
    width = max(dx, dy)
    size = f"{dx:.4g} m x {dy:.4g} m across and {dz:.4g} m tall"
    units = world.meta.get("units")  # None when read with an explicit scale or built in code
    unit = units if isinstance(units, str) else ""
    if width < MIN_EXTENT_M:
        hint = {"hammer": "--units m", "m": "--scale"}.get(unit, "--units m or --scale")
        raise WorldError(f"{world.source}: the mesh is {size}, too small for a map; try {hint}")
    if width > MAX_EXTENT_M:
        hint = {"m": "--units hammer", "hammer": "--scale"}.get(unit, "--units hammer or --scale")
        raise WorldError(f"{world.source}: the mesh is {size}, too large for a map; try {hint}")
    if dz > min(dx, dy):
        raise WorldError(
            f"{world.source}: the mesh is {size}, taller than one of its horizontal sides: "
            "it is probably not Z-up; try --up-axis y"
        )


def write_obj(world: World, path: str | os.PathLike[str], *, units: str = "hammer") -> None:
    """Write the world as a Wavefront OBJ (shared vertices, z up) in `units`, atomically.

    Coordinates are written with the shortest text that reads back to the same float64, so
    `read_mesh(path, units=units)` returns the same triangles (exactly when units="m").
    """
    path = Path(path)
    factor = _metres_per_unit(path, units, None)
    vertices, indices = world.vertices_and_indices()
    vertices = vertices / factor
    lines = [
        f"# {world.name}: {world.num_triangles} triangles, {units} units "
        f"({factor:g} m per unit), x east, y north, z up\n",
        *(f"v {x!r} {y!r} {z!r}\n" for x, y, z in vertices.tolist()),
        *(f"f {a} {b} {c}\n" for a, b, c in (indices + 1).tolist()),
    ]
    write_atomic(path, "".join(lines).encode("ascii"))


def write_tri(world: World, path: str | os.PathLike[str], *, units: str = "hammer") -> None:
    """Write the world as an awpy-style `.tri` (float32, Hammer units by default), atomically."""
    path = Path(path)
    factor = _metres_per_unit(path, units, None)
    write_atomic(path, (world.triangles / factor).astype("<f4").tobytes())


def _metres_per_unit(path: Path, units: str, scale: float | None) -> float:
    """Metres per file unit: `scale` when given, else the factor of the named `units`."""
    if units not in UNITS:
        raise WorldError(f"{path}: unknown units {units!r} (expected one of: {', '.join(UNITS)})")
    if scale is None:
        return UNITS[units]
    if isinstance(scale, bool) or not isinstance(scale, numbers.Real):
        raise WorldError(f"{path}: scale must be a number, got {scale!r}")
    if not np.isfinite(scale) or scale <= 0:
        raise WorldError(f"{path}: scale must be a positive finite number, got {scale!r}")
    return float(scale)


def _up_rotation(path: Path, up_axis: str) -> tuple[str, np.ndarray]:
    """The normalised up-axis name and its rotation onto +z."""
    key = up_axis.strip().lower().removeprefix("+") if isinstance(up_axis, str) else None
    if key not in UP_AXES:
        raise WorldError(
            f"{path}: unknown up axis {up_axis!r} (expected one of: {', '.join(UP_AXES)})"
        )
    return key, UP_AXES[key]


def _offset(path: Path, offset: Sequence[float]) -> np.ndarray:
    try:
        shift = np.asarray(offset, dtype=np.float64)
    except (TypeError, ValueError):
        raise WorldError(f"{path}: offset must be three numbers, got {offset!r}") from None
    if shift.shape != (3,) or not np.all(np.isfinite(shift)):
        raise WorldError(f"{path}: offset must be three finite numbers, got {offset!r}")
    return shift


def _read_bytes(path: Path) -> bytes:
    """The file's bytes, after checking it is a readable, non-empty mesh file of a known type."""
    if not path.suffix:
        raise WorldError(f"{path}: no file extension (expected {' or '.join(FORMATS)})")
    if path.suffix.lower() not in FORMATS:
        raise WorldError(
            f"{path}: unknown mesh format {path.suffix!r} (expected {' or '.join(FORMATS)})"
        )
    if path.is_dir():
        raise WorldError(f"{path}: is a directory, not a mesh file")
    if not path.exists():
        raise WorldError(f"{path}: no such mesh file")
    with open_regular(path, WorldError) as handle:  # a FIFO or a device is refused unopened
        try:
            data = handle.read()
        except OSError as error:
            raise WorldError(f"{path}: cannot read: {error.strerror or error}") from None
    if not data:
        raise WorldError(f"{path}: the file is empty")
    return data


def _parse_tri(data: bytes, path: Path) -> np.ndarray:
    """(T, 3, 3) float32 triangles of an awpy `.tri` file, in file units."""
    if len(data) % _TRI_BYTES:
        raise WorldError(
            f"{path}: {len(data)} bytes is not a multiple of {_TRI_BYTES} "
            "(9 float32 per triangle): truncated or not a .tri file"
        )
    return _finite(np.frombuffer(data, dtype="<f4").reshape(-1, 3, 3), path)


def _parse_awmh(data: bytes, path: Path) -> np.ndarray:
    """(T, 3, 3) float32 triangles of an awpy 3 `.mesh` file, in file units. The counts of
    the header are checked against the file's size before anything is allocated."""
    if len(data) < _AWMH_HEADER.size or data[:4] != _AWMH:
        raise WorldError(f"{path}: not an awpy .mesh file (it does not start with AWMH)")
    _, version, vertices, triangles = _AWMH_HEADER.unpack_from(data)
    if version != _AWMH_VERSION:
        raise WorldError(f"{path}: awpy .mesh version {version}; this decoy reads version 1")
    size = _AWMH_HEADER.size + 12 * vertices + 12 * triangles
    if len(data) < size:
        raise WorldError(
            f"{path}: truncated: its header promises {vertices:,} vertices and {triangles:,} "
            f"triangles ({size:,} bytes), the file has {len(data):,} bytes"
        )
    if triangles == 0:
        raise WorldError(f"{path}: the mesh has no triangles")
    start = _AWMH_HEADER.size
    points = np.frombuffer(data, "<f4", 3 * vertices, start).reshape(-1, 3)
    corners = np.frombuffer(data, "<u4", 3 * triangles, start + 12 * vertices).reshape(-1, 3)
    outside = corners >= vertices
    if outside.any():
        t = int(np.argmax(outside.any(axis=1)))
        raise WorldError(
            f"{path}: triangle {t} refers to vertex {int(corners[t].max())}, but {vertices:,} "
            "vertices are defined"
        )
    return _finite(points[corners], path)


def _finite(triangles: np.ndarray, path: Path) -> np.ndarray:
    """The triangles, when none has a NaN or infinite coordinate."""
    bad = ~np.isfinite(triangles).all(axis=(1, 2))
    if bad.any():
        raise WorldError(
            f"{path}: triangle {int(np.argmax(bad))} has a NaN or infinite coordinate "
            f"({int(bad.sum())} such triangles)"
        )
    return triangles


def _parse_obj(data: bytes, path: Path) -> np.ndarray:
    """(T, 3, 3) float64 triangles of a Wavefront OBJ file, in file units, fan-triangulated."""
    coords: list[str] = []  # x, y, z text of every vertex, in order
    vertex_lines: list[int] = []
    refs: list[str] = []  # vertex references of every face, in order
    face_sizes: list[int] = []
    face_lines: list[int] = []
    face_known: list[int] = []  # vertices defined before each face (for negative references)
    text = data.removeprefix(b"\xef\xbb\xbf").decode("latin-1")  # numbers are ASCII; skip a BOM
    for number, line in enumerate(text.splitlines(), start=1):
        parts = line.split()
        if not parts:
            continue
        key = parts[0]
        if key == "v":
            if len(parts) < 4:
                raise WorldError(f"{path}: line {number}: a vertex needs x, y and z")
            coords += parts[1:4]
            vertex_lines.append(number)
        elif key == "f":
            if len(parts) < 4:
                raise WorldError(f"{path}: line {number}: a face needs at least 3 vertices")
            refs += parts[1:]
            face_sizes.append(len(parts) - 1)
            face_lines.append(number)
            face_known.append(len(vertex_lines))
    if not face_sizes:
        raise WorldError(f"{path}: the OBJ file has no faces")

    vertices = _numbers(coords, np.float64, path, lambda i: vertex_lines[i // 3]).reshape(-1, 3)
    bad = ~np.isfinite(vertices).all(axis=1)
    if bad.any():
        bad_line = vertex_lines[int(np.argmax(bad))]
        raise WorldError(f"{path}: line {bad_line}: vertex has a NaN or infinite coordinate")

    sizes = np.asarray(face_sizes, dtype=np.int64)
    ref_face = np.repeat(np.arange(len(sizes)), sizes)
    index_text = [r.partition("/")[0] for r in refs]
    index = _numbers(index_text, np.int64, path, lambda i: face_lines[ref_face[i]])
    known = np.asarray(face_known, dtype=np.int64)[ref_face]
    resolved = np.where(index > 0, index - 1, known + index)
    missing = (index == 0) | (resolved < 0) | (resolved >= len(vertices))
    if missing.any():
        i = int(np.argmax(missing))
        count = len(vertices) if index[i] > 0 else int(known[i])
        raise WorldError(
            f"{path}: line {face_lines[ref_face[i]]}: face refers to vertex {index_text[i]}, "
            f"but {count} vertices are defined"
        )

    # Fan triangulation: a face with k corners starting at s gives (s, s+j, s+j+1), j = 1..k-2.
    tris_per_face = sizes - 2
    start = np.cumsum(sizes) - sizes
    tri_face = np.repeat(np.arange(len(sizes)), tris_per_face)
    j = np.arange(len(tri_face)) - np.repeat(
        np.cumsum(tris_per_face) - tris_per_face, tris_per_face
    )
    first = start[tri_face]
    corners = np.stack([first, first + j + 1, first + j + 2], axis=1)
    return vertices[resolved[corners]]


def _numbers(
    texts: list[str], dtype: type[np.generic], path: Path, line_of: Callable[[int], int]
) -> np.ndarray:
    """Convert number texts in one go; on failure name the first bad value and its line."""
    try:
        return np.array(texts, dtype=dtype)
    except (ValueError, OverflowError):
        bad = next(i for i, text in enumerate(texts) if not _is_number(text, dtype))
    raise WorldError(f"{path}: line {line_of(bad)}: {texts[bad]!r} is not a valid number")


def _is_number(text: str, dtype: type[np.generic]) -> bool:
    try:
        np.array(text, dtype=dtype)
    except (ValueError, OverflowError):
        return False
    return True
