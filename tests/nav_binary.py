"""Tiny CS2 binary `.nav` files, generated for tests (not real data), in the layout awpy 3 reads.

`write_binary_nav(path, polygons, connections)` writes nav areas (convex polygons, Hammer units,
z up) and their directed connections as a Source 2 nav mesh file, versions 30 to 36, so the
binary path of `decoy_cli.world.nav_json.read_nav` (awpy 3's `NavMesh`) can be tested without a
file from the game. Only what awpy 3 reads is written, all little-endian:

    header    u32 magic 0xFEEDFACE, u32 version, u32 sub-version, u32 flags (bit 0: analyzed)
    v36       an empty KV3 document (8-byte aligned)
    v31+      corner pool: u32 n, n x (f32 x, y, z); polygons: u32 n, n x (u8 corners,
              corners x u32 pool index, v35+: i32 -1)
    v32+      u32 0
    v35+      u32 0 (an empty table of named markers)
    v36       a second empty KV3 document
    areas     u32 n, then per area: u32 id, i64 dynamic attribute flags, u8 hull index,
              v31+: u32 polygon index / v30: u32 n + n x (f32 x, y, z) corners,
              u32 0, per edge (one per corner): u32 n + n x (u32 neighbour id, u32 edge id),
              u8 0 + u32 0 (legacy hiding spot and encounter counts),
              u32 n + ladder ids above, u32 n + ladder ids below (none here)
    ladders   u32 0

A real file goes on after the ladders (generation metadata, a KV3 document); awpy 3 stops
reading after the areas, so none of that is written. The game stores each connection on the
edge of its area it crosses, and awpy lists an area's neighbours edge by edge; here each goes on
the edge nearest its neighbour, or a later one where that would put it before a connection given
earlier, so awpy lists them in the order given (duplicates once). Its edge id, which no reader
here uses, is the neighbour's edge nearest (a guess at what the game writes).
"""

from __future__ import annotations

import struct
from collections.abc import Sequence
from pathlib import Path

Point = tuple[float, float, float]

MAGIC = 0xFEEDFACE
VERSIONS = range(30, 37)
"""The binary nav versions awpy 3 reads (CS2 ships 35 and 36)."""


def write_binary_nav(
    path: str | Path,
    polygons: Sequence[Sequence[Point]],
    connections: Sequence[tuple[int, int]],
    version: int = 35,
    *,
    area_ids: Sequence[int] | None = None,
    sub_version: int = 1,
) -> Path:
    """Write `polygons` (each 3+ corners (x, y, z), Hammer units) as the areas of a binary CS2
    nav, area k with id `area_ids[k]` (default k + 1), and `connections` ((from, to) indices
    into `polygons`) as its directed links; returns the path."""
    if version not in VERSIONS:
        raise ValueError(f"nav version {version}: awpy 3 reads 30-36")
    polys = [[(float(x), float(y), float(z)) for x, y, z in polygon] for polygon in polygons]
    if any(not 3 <= len(polygon) <= 255 for polygon in polys):
        raise ValueError("each polygon needs 3 to 255 corners")
    ids = list(range(1, len(polys) + 1)) if area_ids is None else [int(a) for a in area_ids]
    if len(ids) != len(polys) or len(set(ids)) != len(ids):
        raise ValueError("one distinct area id per polygon")
    edges: list[list[list[tuple[int, int]]]] = [[[] for _ in p] for p in polys]
    last_edge = [0] * len(polys)
    for a, b in connections:
        if not (0 <= a < len(polys) and 0 <= b < len(polys)):
            raise ValueError(f"connection {(a, b)} names no polygon")
        edge, their_edge = _facing_edges(polys[a], polys[b])
        last_edge[a] = max(edge, last_edge[a])  # never before an earlier one: order is kept
        edges[a][last_edge[a]].append((ids[b], their_edge))

    out = bytearray(struct.pack("<4I", MAGIC, version, sub_version, 1))
    if version >= 36:
        _empty_kv3(out)
    if version >= 31:
        pool: dict[bytes, int] = {}  # corners shared by adjacent areas are stored once
        indices = [[pool.setdefault(_vec3(p), len(pool)) for p in polygon] for polygon in polys]
        out += struct.pack("<I", len(pool)) + b"".join(pool)
        out += struct.pack("<I", len(polys))
        for corner_indices in indices:
            out += struct.pack(f"<B{len(corner_indices)}I", len(corner_indices), *corner_indices)
            if version >= 35:
                out += struct.pack("<i", -1)
    if version >= 32:
        out += struct.pack("<I", 0)
    if version >= 35:
        out += struct.pack("<I", 0)
    if version >= 36:
        _empty_kv3(out)

    out += struct.pack("<I", len(polys))
    for k, polygon in enumerate(polys):
        out += struct.pack("<IqB", ids[k], 0, 0)  # id, dynamic attribute flags, hull index
        if version >= 31:
            out += struct.pack("<I", k)
        else:
            out += struct.pack("<I", len(polygon)) + b"".join(_vec3(p) for p in polygon)
        out += struct.pack("<I", 0)
        for links in edges[k]:
            out += struct.pack("<I", len(links))
            for neighbour, their_edge in links:
                out += struct.pack("<2I", neighbour, their_edge)
        out += struct.pack("<BI", 0, 0)  # legacy hiding spot and encounter path counts
        out += struct.pack("<2I", 0, 0)  # no ladders above, none below
    out += struct.pack("<I", 0)  # the file's ladders: none

    path = Path(path)
    path.write_bytes(bytes(out))
    return path


def _vec3(point: Point) -> bytes:
    return struct.pack("<3f", *point)


def _midpoints(polygon: list[Point]) -> list[Point]:
    ends = zip(polygon, polygon[1:] + polygon[:1], strict=True)
    return [((x + u) / 2, (y + v) / 2, (z + w) / 2) for (x, y, z), (u, v, w) in ends]


def _facing_edges(ours: list[Point], theirs: list[Point]) -> tuple[int, int]:
    """The edge of `ours` and the edge of `theirs` whose midpoints are nearest each other."""
    pairs = [
        (sum((p[j] - q[j]) ** 2 for j in range(3)), i, k)
        for i, p in enumerate(_midpoints(ours))
        for k, q in enumerate(_midpoints(theirs))
    ]
    _, edge, their_edge = min(pairs)
    return edge, their_edge


def _empty_kv3(out: bytearray) -> None:
    """Append an empty, uncompressed KV3 (version 5) document, 8-byte aligned: the header's
    sizes say it has no data, which is all a reader that skips it looks at."""
    out += bytes(-len(out) % 8)
    out += struct.pack("<I", 0x4B563305)  # "\x053VK"
    out += bytes(16)  # format GUID
    out += struct.pack("<IHH", 0, 0, 0)  # uncompressed; dictionary id, frame size
    out += struct.pack("<4I2H", 0, 0, 0, 0, 0, 0)  # byte/type/object/array counts
    out += struct.pack("<4i", 0, 0, 0, 0)  # total sizes (uncompressed, compressed), blocks, blobs
    out += struct.pack("<Ii", 0, 0)  # v4+: two-byte count, compressed block size
    out += struct.pack("<4i", 0, 0, 0, 0)  # v5+: buffer sizes (uncompressed, compressed) x 2
    out += bytes(4 * 8)  # v5+: the second buffer's counts
