"""The ladders of a CS:GO `.nav` file (the binary navigation mesh the game writes).

awpy 1.3.1's nav data, which the built-in maps come from, kept the areas and their links but no
ladders, so the spots players reach only by climbing (de_nuke's Heaven and roofs, de_train's
sniper's nest) were out of reach. The game's `.nav` file keeps them: this module reads a
version-16 file (CS:GO) far enough to get to its ladder list, which follows the areas.

Layout (little-endian; facts of the format, as the Source SDK writes it): a header (magic
0xFEEDFACE, version, sub-version, the BSP's size, an "analyzed" byte), the place names (u16
count, then u16 length + bytes each), an "unnamed areas" byte, the areas (u32 count, each of
variable length: id, attribute flags, two corners, two corner heights, links in four
directions, hiding spots, encounter paths, place, ladder links in two directions, occupy times,
corner light, visible areas, an inherited-visibility id, and on sub-version 1 CS:GO's approach
spots), then the ladders (u32 count, 60 bytes each: id, width, top x y z, bottom x y z, length,
facing direction, five area ids).
"""

from __future__ import annotations

import struct
from pathlib import Path

import numpy as np

from decoy_cli.errors import WorldError

NAV_MAGIC = 0xFEEDFACE
NAV_VERSION = 16
"""The version CS:GO writes; older and newer layouts differ and are refused."""
MAX_NAV_BYTES = 64 * 1024 * 1024
"""A CS:GO nav file is a few hundred kilobytes; anything this large is not one."""
SUB_VERSIONS = (0, 1)
"""CS:GO's sub-versions: 1 adds approach spots to every area; others are refused."""
LADDER_RECORD = "If3f3ffI5I"
"""One ladder in the file: id, width, top, bottom, length, facing direction, five area ids."""
LADDER_COLUMNS = (
    "ladder_id",
    "width",
    "top_x",
    "top_y",
    "top_z",
    "bottom_x",
    "bottom_y",
    "bottom_z",
)
"""One ladder: its id in the file, its width and the centres of its top and bottom (Hammer u)."""


class _Reader:
    """Sequential little-endian reads that fail with a WorldError past the end."""

    def __init__(self, data: bytes, origin: str) -> None:
        self.data, self.offset, self.origin = data, 0, origin

    def read(self, fmt: str) -> tuple:
        size = struct.calcsize("<" + fmt)
        if self.offset + size > len(self.data):
            raise WorldError(f"{self.origin}: truncated nav file (ends at byte {len(self.data)})")
        values = struct.unpack_from("<" + fmt, self.data, self.offset)
        self.offset += size
        return values

    def one(self, fmt: str) -> int | float:
        return self.read(fmt)[0]

    def skip(self, count: int, each: int) -> None:
        """Skip `count` records of `each` bytes, refusing counts the file cannot hold."""
        if count * each > len(self.data) - self.offset:
            raise WorldError(f"{self.origin}: a count of {count} runs past the end of the file")
        self.offset += count * each


def read_nav_ladders(path: str | Path) -> np.ndarray:
    """The ladders of a CS:GO `.nav` file, (L, 8) in `LADDER_COLUMNS` order (Hammer units); a
    WorldError for a file that is not a version-16 nav file or is cut short."""
    path = Path(path)
    try:
        if not path.exists():
            raise WorldError(f"cannot read nav file {path}: no such file")
        if not path.is_file():
            raise WorldError(f"{path}: not a nav file (not a regular file)")
        with open(path, "rb") as f:
            data = f.read(MAX_NAV_BYTES + 1)
    except OSError as error:
        raise WorldError(f"cannot read nav file {path}: {error.strerror}") from None
    if len(data) > MAX_NAV_BYTES:
        raise WorldError(f"{path}: larger than {MAX_NAV_BYTES} bytes, too large for a nav file")
    r = _Reader(data, str(path))
    magic, version = r.read("II")
    if magic != NAV_MAGIC:
        raise WorldError(f"{path}: not a nav file (no 0xFEEDFACE header)")
    if version != NAV_VERSION:
        raise WorldError(f"{path}: nav version {version}; only CS:GO's {NAV_VERSION} is read")
    sub_version = r.one("I")
    if sub_version not in SUB_VERSIONS:
        raise WorldError(f"{path}: nav sub-version {sub_version}; CS:GO's are 0 and 1")
    r.read("IB")  # BSP size, analyzed
    for _ in range(int(r.one("H"))):  # place names
        r.skip(int(r.one("H")), 1)
    r.one("B")  # has unnamed areas
    for _ in range(int(r.one("I"))):
        _skip_area(r, int(sub_version))
    count = int(r.one("I"))
    left = len(data) - r.offset
    if count * struct.calcsize("<" + LADDER_RECORD) > left:
        raise WorldError(f"{path}: {count} ladders do not fit in the file's last {left} bytes")
    ladders = np.zeros((count, len(LADDER_COLUMNS)))
    for k in range(count):
        # the five area ids (at its top: forward, left, right, behind; at its bottom) are unused
        ladder_id, width, tx, ty, tz, bx, by, bz = r.read(LADDER_RECORD)[:8]
        ladders[k] = (ladder_id, width, tx, ty, tz, bx, by, bz)
    if not np.all(np.isfinite(ladders)):
        raise WorldError(f"{path}: a ladder has a NaN or infinite coordinate")
    if np.any(ladders[:, 4] <= ladders[:, 7]):
        raise WorldError(f"{path}: a ladder's top is not above its bottom")
    return ladders


def _skip_area(r: _Reader, sub_version: int) -> None:
    """Read past one area of a version-16 file."""
    r.read("II3f3f2f")  # id, attributes, north-west and south-east corners, two corner heights
    for _ in range(4):  # links in each direction
        r.skip(int(r.one("I")), 4)
    r.skip(int(r.one("B")), 17)  # hiding spots: id, x y z, flags
    for _ in range(int(r.one("I"))):  # encounter paths: from id, dir, to id, dir, spots
        r.read("IBIB")
        r.skip(int(r.one("B")), 5)
    r.one("H")  # place
    for _ in range(2):  # ladders up, down
        r.skip(int(r.one("I")), 4)
    r.read("2f4f")  # earliest occupy times, corner light
    r.skip(int(r.one("I")), 5)  # visible areas: id, attributes
    r.one("I")  # inherit visibility from
    if sub_version == 1:  # CS:GO's approach spots: here, previous, how, next, how
        r.skip(int(r.one("B")), 14)
