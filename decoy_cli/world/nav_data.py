"""The nav mesh of a built-in map as data: the areas, their places and links, the ladders, the
radar transform, and the boxes the nav mesh lacks (`world_patches.csv`), read from the map's
assets.
"""

from __future__ import annotations

import csv
from dataclasses import dataclass, field, replace
from functools import cache
from pathlib import Path
from typing import Any

import numpy as np

from decoy_cli.csgo import BUILTIN_MAP, HAMMER_TO_M, MAP_NAMES
from decoy_cli.errors import WorldError
from decoy_cli.package_data import packaged_dir
from decoy_cli.reading import load_json
from decoy_cli.text import shortened, visible

REGIONS = ("t_spawn", "ct_spawn", "bombsite_a", "bombsite_b")
"""Regions the simulator and the replay use; each map's `map.json` names the nav places of each
(usually TSpawn, CTSpawn, BombsiteA and BombsiteB)."""


@dataclass(frozen=True)
class NavMesh:
    """Nav areas as arrays (Hammer units): rectangle bounds, corner heights, places, links."""

    area_id: np.ndarray  # (A,) int64
    place: np.ndarray  # (A,) str
    x_min: np.ndarray
    y_min: np.ndarray
    x_max: np.ndarray
    y_max: np.ndarray
    z_at_min: np.ndarray  # height at (x_min, y_min)
    z_at_max: np.ndarray  # height at (x_max, y_max)
    connections: np.ndarray  # (C, 2) area indices (not ids), directed
    radar: dict[str, float]
    regions: dict[str, tuple[str, ...]]  # region -> the nav places that make it
    ladders: np.ndarray = field(default_factory=lambda: np.zeros((0, 6)))
    """(L, 6) each ladder's top and bottom centre, x y z, Hammer units (`nav_ladders.csv`)."""

    @property
    def num_areas(self) -> int:
        return len(self.area_id)

    @property
    def places(self) -> list[str]:
        """Sorted distinct place names (the empty name excluded)."""
        return sorted({p for p in self.place.tolist() if p})

    def contains(self, points_u: np.ndarray, z_tolerance_u: float, margin_u: float = 0.0):
        """(M, A) mask of points inside each area's rectangle (grown by margin) near its height."""
        x, y, z = points_u[:, 0:1], points_u[:, 1:2], points_u[:, 2:3]
        inside = (
            (x >= self.x_min - margin_u)
            & (x <= self.x_max + margin_u)
            & (y >= self.y_min - margin_u)
            & (y <= self.y_max + margin_u)
        )
        low = np.minimum(self.z_at_min, self.z_at_max)
        high = np.maximum(self.z_at_min, self.z_at_max)
        return inside & (z >= low - z_tolerance_u) & (z <= high + z_tolerance_u)

    def area_of(self, points_m: np.ndarray, max_distance_m: float = 1.0) -> np.ndarray:
        """Index of the nav area under each point (metres), -1 where none is near.

        A point inside several rectangles (two floors) takes the one closest in height; a point
        just outside every rectangle (near a wall) takes the nearest rectangle on its floor.
        """
        pts = np.asarray(points_m, dtype=np.float64).reshape(-1, 3) / HAMMER_TO_M
        out = np.full(len(pts), -1, dtype=np.int64)
        centre_z = (self.z_at_min + self.z_at_max) / 2
        for start in range(0, len(pts), 2048):
            chunk = pts[start : start + 2048]
            dx = np.maximum(0, np.maximum(self.x_min - chunk[:, :1], chunk[:, :1] - self.x_max))
            dy = np.maximum(0, np.maximum(self.y_min - chunk[:, 1:2], chunk[:, 1:2] - self.y_max))
            dz = np.abs(chunk[:, 2:3] - centre_z)
            cost = np.hypot(dx, dy) + 0.25 * dz
            best = np.argmin(cost, axis=1)
            ok = cost[np.arange(len(chunk)), best] <= max_distance_m / HAMMER_TO_M
            out[start : start + len(chunk)] = np.where(ok, best, -1)
        return out


def asset_dir(map_name: str = BUILTIN_MAP) -> Path:
    """Folder of a built-in map's assets (top-level `assets/`, installed as decoy_cli.assets).
    A map name comes from data (a match file, a run's files): only the names of `MAP_NAMES` are
    taken, so no name is a path to read from; any other is a WorldError."""
    if map_name not in MAP_NAMES:
        known = ", ".join(MAP_NAMES)
        shown = visible(shortened(str(map_name)))
        raise WorldError(f"no built-in map {shown!r} (this decoy knows: {known})")
    return packaged_dir("assets") / map_name


@cache
def load_navmesh(map_name: str = BUILTIN_MAP) -> NavMesh:
    """Read the nav areas, connections and radar transform shipped for a built-in map."""
    folder = asset_dir(map_name)
    if not (folder / "nav_areas.csv").is_file():
        raise WorldError(f"no built-in map {map_name!r} (looked in {folder})")
    return read_navmesh(folder)


NAV_COLUMNS = ("x_min", "y_min", "z_at_min", "x_max", "y_max", "z_at_max")
NAV_LADDERS_FILE = "nav_ladders.csv"
"""A map's ladders (`scripts/extract_nav_ladders.py`); maps without ladders have no such file."""
LADDER_ENDS = ("top_x", "top_y", "top_z", "bottom_x", "bottom_y", "bottom_z")


def read_navmesh(folder: Path) -> NavMesh:
    """A map's nav mesh from its folder (`nav_areas.csv`, `nav_connections.csv`, `map.json`);
    a WorldError naming the file and line for a missing or bad value."""
    areas = folder / "nav_areas.csv"
    try:
        with open(areas, newline="") as f:
            rows = list(csv.DictReader(f))
        with open(folder / "nav_connections.csv", newline="") as f:
            links = list(csv.DictReader(f))
        meta: Any = load_json(folder / "map.json", WorldError)
        regions = {region: tuple(meta["regions"][region]) for region in REGIONS}
        radar = {key: float(meta["radar"][key]) for key in ("pos_x", "pos_y", "scale")}
    except (OSError, UnicodeDecodeError, csv.Error, ValueError, KeyError, TypeError) as error:
        raise WorldError(f"{folder}: not a readable map folder ({error})") from None
    values = np.full((len(rows), len(NAV_COLUMNS)), np.nan)
    area_id = np.zeros(len(rows), dtype=np.int64)
    for line, row in enumerate(rows, start=2):
        try:
            area_id[line - 2] = int(row["area_id"])
            values[line - 2] = [float(row[key]) for key in NAV_COLUMNS]
        except (KeyError, TypeError, ValueError):
            values[line - 2] = np.nan
        if not np.all(np.isfinite(values[line - 2])):
            raise WorldError(
                f"{areas}, line {line}: an area needs an id and numbers in "
                f"{', '.join(NAV_COLUMNS)} (corner heights included)"
            )
    index = {int(a): i for i, a in enumerate(area_id)}
    try:
        pairs = [(index[int(r["from_area"])], index[int(r["to_area"])]) for r in links]
    except (KeyError, TypeError, ValueError):
        raise WorldError(f"{folder / 'nav_connections.csv'}: a link names no known area") from None
    col = dict(zip(NAV_COLUMNS, values.T, strict=True))
    nav = NavMesh(
        area_id=area_id,
        place=np.array([r.get("place") or "" for r in rows]),
        x_min=col["x_min"],
        y_min=col["y_min"],
        x_max=col["x_max"],
        y_max=col["y_max"],
        z_at_min=col["z_at_min"],
        z_at_max=col["z_at_max"],
        connections=np.array(pairs, dtype=np.int64).reshape(-1, 2),
        radar=radar,
        regions=regions,
    )
    if (folder / NAV_LADDERS_FILE).is_file():
        nav = replace(nav, ladders=read_ladders(folder / NAV_LADDERS_FILE, nav))
    return nav


def read_ladders(path: Path, nav: NavMesh) -> np.ndarray:
    """The ladders of a `nav_ladders.csv` (`LADDER_ENDS`, Hammer units); a WorldError naming the
    file and line for a malformed row, a ladder whose top is not above its bottom or one off
    the map's nav mesh."""
    wheres, ladders = _number_rows(path, LADDER_ENDS, "ladder")
    bounds = _reach(nav)
    for where, ladder in zip(wheres, ladders, strict=True):
        if not ladder[2] > ladder[5]:
            raise WorldError(f"{where}: the ladder's top is not above its bottom")
        _on_the_map(where, ladder.reshape(2, 3), bounds, "the ladder")
    return ladders


def _number_rows(path: Path, columns: tuple[str, ...], what: str) -> tuple[list[str], np.ndarray]:
    """The rows of a CSV file of numbers in `columns`: where each is ("<file>, line <n>") and
    its values (R, len(columns)); a WorldError for an unreadable file or a row with a missing
    or non-finite value."""
    try:
        with open(path, newline="") as f:
            rows = list(csv.DictReader(f))
    except (OSError, UnicodeDecodeError, csv.Error) as error:
        raise WorldError(f"{path}: not a readable CSV file ({error})") from None
    values = np.zeros((len(rows), len(columns)))
    wheres = [f"{path}, line {line}" for line in range(2, len(rows) + 2)]
    for k, row in enumerate(rows):
        try:
            values[k] = [float(row[key]) for key in columns]
        except (KeyError, TypeError, ValueError):
            values[k] = np.nan
        if not np.all(np.isfinite(values[k])):
            raise WorldError(f"{wheres[k]}: a {what} needs numbers in {', '.join(columns)}")
    return wheres, values


def _reach(nav: NavMesh) -> tuple[np.ndarray, np.ndarray]:
    """(low, high) corners of the nav mesh's bounding box grown by `PATCH_REACH_U`."""
    low = np.array([nav.x_min.min(), nav.y_min.min(), nav.z_at_min.min()]) - PATCH_REACH_U
    high = np.array([nav.x_max.max(), nav.y_max.max(), nav.z_at_max.max()]) + PATCH_REACH_U
    return low, high


def _on_the_map(
    where: str, points: np.ndarray, bounds: tuple[np.ndarray, np.ndarray], what: str
) -> None:
    """A WorldError unless the (P, 3) points lie within `bounds` (`_reach`)."""
    low, high = bounds
    if np.any(points < low) or np.any(points > high):
        raise WorldError(f"{where}: {what} lies off the map's nav mesh")


def load_patches(map_name: str = BUILTIN_MAP) -> np.ndarray:
    """Boxes missing from a built-in map's nav mesh, (B, 6) Hammer units: x_min, y_min, x_max,
    y_max, z_top, z_bottom (none when the map has no `world_patches.csv`)."""
    path = asset_dir(map_name) / "world_patches.csv"
    if not path.is_file():
        return np.zeros((0, 6))
    return read_patches(path, load_navmesh(map_name))


PATCH_COLUMNS = ("x_min", "y_min", "x_max", "y_max", "z_top", "z_bottom")

PATCH_REACH_U = 512.0
"""How far beyond the nav mesh's bounding box a patch or a ladder may reach (Hammer units)."""


def read_patches(path: Path, nav: NavMesh) -> np.ndarray:
    """The boxes of a patches file (`PATCH_COLUMNS`, Hammer units); a WorldError naming the file
    and line for a malformed row, an empty or upside-down box, or one off the map's nav mesh."""
    wheres, boxes = _number_rows(path, PATCH_COLUMNS, "patch")
    bounds = _reach(nav)
    for where, box in zip(wheres, boxes, strict=True):
        x0, y0, x1, y1, top, bottom = box
        if not (x0 < x1 and y0 < y1 and bottom < top):
            raise WorldError(f"{where}: an empty or upside-down box")
        _on_the_map(where, np.array([[x0, y0, bottom], [x1, y1, top]]), bounds, "the box")
    return boxes
