"""A CS2 navigation mesh, in awpy's JSON form or CS2's binary `.nav`, read into polygons.

CS2 nav areas are convex polygons (triangles and quadrilaterals on de_dust2) with a full height
at every corner, not CS:GO's axis-aligned rectangles with two corner heights. awpy 2 writes
them as JSON (`awpy nav FILE.nav`, `awpy get navs`):

    {"version": 35, "sub_version": 1, "is_analyzed": true,
     "areas": {"1": {"area_id": 1, "hull_index": 0, "dynamic_attribute_flags": 0,
                     "corners": [{"x": ..., "y": ..., "z": ...}, ...],
                     "connections": [3, ...], "ladders_above": [], "ladders_below": []}, ...}}

`version` is the binary file's (awpy 2 reads 30-35, awpy 3 30-36); the JSON layout is the same
for each, so those are read and any other is refused. The file may be xz- or gzip-compressed
(as the copy in awpy's source distribution is). A binary `.nav` (a user's `awpy get` files) is
read through awpy 3's `NavMesh` when awpy 3 is installed and checked as the JSON is. Neither
carries place names or ladder positions (only ladder ids): places come from the map's built-in
CS:GO nav (`waypoints/build.py`), and ladder links are counted.
"""

from __future__ import annotations

import lzma
import zlib
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from decoy_cli.errors import WorldError
from decoy_cli.reading import parse_json, read_limited

NAV_VERSIONS = range(30, 37)
"""Binary nav versions of CS2 whose areas awpy writes in this JSON layout."""
MAX_FILE_MB = 64.0
"""A CS2 map's JSON nav is a few megabytes (de_dust2: 1.4 MB); larger is not one."""
MAX_AREAS = 100_000
MAX_CORNERS = 8
"""CS2 writes triangles and quadrilaterals; up to this many corners are read."""
MAX_COORD_U = 32768.0
"""No map coordinate reaches this far from the origin (Hammer units)."""


@dataclass(frozen=True)
class PolygonNav:
    """Nav areas as polygons (Hammer units, z up), counter-clockwise seen from above."""

    area_id: np.ndarray  # (A,) int64
    corners: np.ndarray  # (A, K, 3): the first `sides[a]` rows are the area's corners
    sides: np.ndarray  # (A,) int64, 3..K
    connections: np.ndarray  # (C, 2) area indices (not ids), directed
    version: int
    ladder_links: int
    """Ladder ids the areas name: their positions are not in the JSON form."""
    source: str

    @property
    def num_areas(self) -> int:
        return len(self.area_id)

    def polygon(self, area: int) -> np.ndarray:
        """The (n, 3) corners of one area."""
        return self.corners[area, : self.sides[area]]


def read_nav(path: str | Path) -> PolygonNav:
    """The polygons of a CS2 nav file: CS2's binary `.nav` (through awpy 3), else awpy's JSON
    form (plain, .xz or .gz); a WorldError naming the file for anything that is not one."""
    path = Path(path)
    limit = int(MAX_FILE_MB * 1e6)
    data = read_limited(path, limit, WorldError)  # a regular file of at most `limit` bytes
    if path.suffix.lower() == ".nav":
        return _polygons(_binary_document(path), path)
    return _polygons(parse_json(_decompressed(data, limit, path), str(path), WorldError), path)


def _binary_document(path: Path) -> dict[str, object]:
    """A binary CS2 nav read by awpy 3's `NavMesh`, in the JSON form's shape."""
    try:
        from awpy import NavMesh
    except ImportError:
        raise WorldError(
            f"{path}: a binary CS2 nav is read through awpy 3 (pip install -e '.[cs2]'); or "
            "give its JSON form (awpy 2: `awpy nav FILE.nav`)"
        ) from None
    try:
        mesh = NavMesh(path)
        areas: dict[str, object] = {}
        for area_id in mesh.areas["area_id"].to_list():
            area: Mapping[str, Any] = mesh.area(area_id) or {}
            areas[str(area_id)] = {
                "area_id": area_id,
                "corners": [{"x": x, "y": y, "z": z} for x, y, z in area.get("corners", [])],
                **{name: list(area.get(name, [])) for name in _ID_LISTS},
            }
    except (ValueError, OSError, TypeError, KeyError) as error:
        raise WorldError(f"{path}: not a CS2 nav file awpy 3 reads ({error})") from None
    return {"version": mesh.version, "areas": areas}


def _polygons(document: object, path: Path) -> PolygonNav:
    """The polygons of a nav in the JSON form's shape, checked."""
    areas = document.get("areas") if isinstance(document, dict) else None
    if not isinstance(document, dict) or not isinstance(areas, dict):
        raise WorldError(f"{path}: not an awpy JSON nav file (no 'areas' object)")
    version = document.get("version")
    if not isinstance(version, int) or version not in NAV_VERSIONS:
        raise WorldError(
            f"{path}: nav version {version!r}; this reader knows CS2's "
            f"{NAV_VERSIONS.start}-{NAV_VERSIONS.stop - 1} (awpy's JSON form)"
        )
    if not 0 < len(areas) <= MAX_AREAS:
        raise WorldError(f"{path}: {len(areas):,} areas; a map has 1 to {MAX_AREAS:,}")
    ids = np.zeros(len(areas), dtype=np.int64)
    corners = np.zeros((len(areas), MAX_CORNERS, 3))
    sides = np.zeros(len(areas), dtype=np.int64)
    links: list[tuple[int, int]] = []
    ladder_links = 0
    for k, (key, area) in enumerate(areas.items()):
        where = f"{path}: area {str(key)[:20]!r}"
        if not isinstance(area, dict):
            raise WorldError(f"{where} is not an object")
        area_id = area.get("area_id")
        if not isinstance(area_id, int) or str(area_id) != str(key) or area_id < 0:
            raise WorldError(f"{where}: its area_id must be the key's whole number")
        ids[k] = area_id
        points = _corners(area.get("corners"), where)
        sides[k] = len(points)
        corners[k, : len(points)] = points
        corners[k, len(points) :] = points[-1]
        lists = {name: _ids(area.get(name, []), f"{where}: {name}") for name in _ID_LISTS}
        links += [(k, v) for v in lists["connections"]]
        ladder_links += len(lists["ladders_above"]) + len(lists["ladders_below"])
    index = {int(a): k for k, a in enumerate(ids)}
    unknown = [b for _, b in links if b not in index]
    if unknown:
        raise WorldError(f"{path}: a connection names area {unknown[0]}, which the file lacks")
    pairs = np.array([(a, index[b]) for a, b in links if index[b] != a], dtype=np.int64)
    return PolygonNav(
        area_id=ids,
        corners=corners,
        sides=sides,
        connections=pairs.reshape(-1, 2),
        version=version,
        ladder_links=ladder_links,
        source=str(path),
    )


_ID_LISTS = ("connections", "ladders_above", "ladders_below")


def _ids(value: object, where: str) -> list[int]:
    """`value` when it is a list of area ids, else a WorldError."""
    if not isinstance(value, list) or not all(isinstance(v, int) and v >= 0 for v in value):
        raise WorldError(f"{where} must be a list of area ids")
    return value


def _decompressed(data: bytes, limit: int, path: Path) -> bytes:
    """`data` itself, or what it unpacks to when xz or gzip (at most `limit` bytes)."""
    try:
        if data.startswith(b"\xfd7zXZ\x00"):
            xz = lzma.LZMADecompressor()
            out, complete = xz.decompress(data, max_length=limit + 1), xz.eof
        elif data.startswith(b"\x1f\x8b"):
            gz = zlib.decompressobj(wbits=31)
            out, complete = gz.decompress(data, limit + 1), gz.eof
        else:
            return data
    except (lzma.LZMAError, zlib.error, EOFError) as error:
        raise WorldError(f"{path}: a damaged compressed file ({error})") from None
    if len(out) > limit:
        raise WorldError(f"{path}: unpacks to more than {MAX_FILE_MB:g} MB, too large for a nav")
    if not complete:
        raise WorldError(f"{path}: a damaged compressed file (it ends before its data does)")
    return out


def _corners(value: object, where: str) -> np.ndarray:
    """The (n, 3) corners of an area, counter-clockwise, or a WorldError."""
    if not isinstance(value, list) or not 3 <= len(value) <= MAX_CORNERS:
        raise WorldError(f"{where}: corners must be a list of 3 to {MAX_CORNERS} points")
    try:
        points = np.array([[c["x"], c["y"], c["z"]] for c in value], dtype=np.float64)
    except (TypeError, KeyError, ValueError):
        raise WorldError(f"{where}: each corner needs numbers x, y and z") from None
    if not np.all(np.isfinite(points)) or np.any(np.abs(points) > MAX_COORD_U):
        raise WorldError(f"{where}: a corner lies outside any map (|coordinate| > {MAX_COORD_U:g})")
    x, y = points[:, 0], points[:, 1]
    twice_area = float(np.dot(x, np.roll(y, -1)) - np.dot(np.roll(x, -1), y))
    return points if twice_area >= 0 else points[::-1]
