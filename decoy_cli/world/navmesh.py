"""The built-in de_dust2 world, made from the real CS:GO navigation mesh (awpy 1.3.1 slice).

The nav mesh is 1,118 axis-aligned rectangles ("areas") with a place name and the heights of two
opposite corners, plus the list of connected area pairs. `nav_world()` turns it into a triangle
world that a physics engine can use:

* **Floors.** Each area is a bilinear quad. awpy 1.x dropped two corner heights of each area;
  they are fitted by least squares so that touching areas meet along their shared edges (without
  that fit, seams show steps of about 12 u at the 90th percentile).
* **Step faces.** Vertical faces between touching areas at different heights, so a ledge is a
  ledge and not a gap.
* **Bridges.** Connected areas separated by a small gap (up to 32 u, typically a jump onto a box)
  get a floor across the gap (each half at its own side's height, with a step face between).
* **Walls.** Area edges that border no other area become vertical walls. Nav areas stop about
  16 u (half a player hull) short of the real walls, so walls are pushed out by up to 16 u, capped
  at half the gap to the next area, and the floor is extended under the push.

* **Patches.** Solid boxes the nav mesh lacks but real players stand on, one per row of
  `world_patches.csv` (Hammer units, with what each is and the evidence). The one so far is the
  step in front of the mid boxes: without it the boxes were reachable only from behind, a 28 m
  detour, and a quarter of all replay lateness on the real T rounds came from there.
* **Ledge faces.** A side facing a floor more than a jump higher or lower within 128 u gets a
  face up (or down) to that floor instead of a full 3.5 m wall, so the top of a box or ledge
  stays open to a jump from below (the mid boxes again: their nav area starts 50 u behind the
  face).

Everything is computed in Hammer units and returned in metres. Line of sight in this world is
approximate: holes in the nav mesh become walls, and windows, low cover and door gaps vanish.
"""

from __future__ import annotations

from functools import cache

import numpy as np

from decoy_cli.csgo import BUILTIN_MAP, HAMMER_TO_M
from decoy_cli.world.nav_data import (
    REGIONS,
    NavMesh,
    asset_dir,
    load_navmesh,
    load_patches,
)
from decoy_cli.world.nav_geometry import box_triangles, build_nav_triangles
from decoy_cli.world.world import World

__all__ = [
    "BUILTIN_MAP",
    "REGIONS",
    "NavMesh",
    "asset_dir",
    "load_navmesh",
    "load_patches",
    "nav_world",
]


PatchBoxes = tuple[tuple[float, ...], ...]
"""Patch boxes as `PATCH_COLUMNS` rows in Hammer units, hashable (a cache key)."""


@cache
def nav_world(map_name: str = BUILTIN_MAP, patches: PatchBoxes | None = None) -> World:
    """The built-in triangle world of a map, in metres (cached per process), with the map's
    shipped patches, or with `patches` instead (`()`: the bare nav world, as patches are
    learned on)."""
    nav = load_navmesh(map_name)
    shipped = load_patches(map_name) if patches is None else np.array(patches).reshape(-1, 6)
    boxes = [box_triangles(*b) for b in shipped]
    tris = np.concatenate([build_nav_triangles(nav), *boxes]) * HAMMER_TO_M
    return World(
        triangles=tris,
        name=map_name,
        source=f"built-in {map_name} nav mesh (awpy 1.3.1)",
        meta={
            "kind": "navmesh",
            "areas": nav.num_areas,
            "patches": len(boxes),
            # given patches travel with a graph built on this world (graph_world reads them)
            **({} if patches is None else {"patch_boxes": [list(b) for b in patches]}),
        },
    )
