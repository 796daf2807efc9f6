"""A CS2 map's world from its nav mesh file, checked to be the map it claims to be.

The JSON form names no map, so the file is checked against the map's built-in (CS:GO) nav
mesh: CS2 kept the coordinates of the maps it remade, so most of a CS2 nav's areas lie on the
CS:GO nav of the same map and few on another map's (benchmarks/studies/cs2_world.py prints the
shares for de_dust2's file). A file below `SAME_MAP_SHARE` is refused.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from decoy_cli.csgo import HAMMER_TO_M
from decoy_cli.errors import WorldError
from decoy_cli.world.nav_data import load_navmesh
from decoy_cli.world.nav_json import PolygonNav, read_nav
from decoy_cli.world.nav_polygons import polygon_world
from decoy_cli.world.world import World

SAME_MAP_SHARE = 0.6
"""Least share of the file's area centres within `SAME_MAP_REACH_M` of the map's built-in nav."""
SAME_MAP_REACH_M = 1.0


def cs2_world(path: str | Path, map_name: str) -> World:
    """The world of the CS2 nav file `path` of the built-in map `map_name`; a WorldError for a
    file that is not a nav mesh of that map."""
    nav = read_nav(path)
    share = on_map_share(nav, map_name)
    if share < SAME_MAP_SHARE:
        raise WorldError(
            f"{path}: not a nav mesh of {map_name} (only {share:.0%} of its areas lie on "
            f"{map_name}'s; a nav of the map has at least {SAME_MAP_SHARE:.0%}): check --map"
        )
    return polygon_world(nav, map_name)


def on_map_share(nav: PolygonNav, map_name: str) -> float:
    """Share of the nav's area centres within reach of the built-in nav mesh of `map_name`."""
    centres = np.array([nav.polygon(a).mean(axis=0) for a in range(nav.num_areas)])
    found = load_navmesh(map_name).area_of(centres * HAMMER_TO_M, SAME_MAP_REACH_M)
    return float(np.mean(found >= 0))
