"""Hand-made triangle worlds (metres, x east, y north, z up) for the waypoint builder's tests.

Each world is built from axis-aligned floors, walls, boxes and ramps, and carries the seed point
its tests start the lattice from in `world.meta["seed"]` (on the floor, one lattice point). The
numbers each test relies on (heights, extents) are module constants, so tests state their
expectations from the geometry, not from a previous run. No wall or floor edge lies exactly on a
lattice line of its world's seed (0.7 m spacing): a pybullet ray that ends exactly on a triangle
misses it, so such a line grows nodes standing in the wall, which the builder then nudges or
prunes; the tests here are about ordinary geometry.

Usage from a test module: `from worlds import room, jump_box_world, ...`.
"""

from __future__ import annotations

import numpy as np

from decoy_cli.waypoints.graph import WaypointGraph
from decoy_cli.waypoints.lattice import LatticeResult
from decoy_cli.world.world import World

WALL_HEIGHT = 3.0

ROOM_SIZE = 5.0
"""Side of the square room; its seed is the centre, so lattice lines run 0.4 m from the walls."""

LEDGE_Z = 1.5
"""Height of the raised platform of `ledge_world` (above a crouch-jump, below the safe fall)."""
LEDGE_X = 6.0
"""The platform's west face (x = LEDGE_X): the lower floor lies west of it, the platform east."""

BOX_Z = 0.9
"""Height of the box of `jump_box_world` (above the step height, below a crouch-jump)."""
BOX = (3.0, 3.0, 4.5, 4.5)
"""The box's footprint (x0, y0, x1, y1); the lattice points 3.3 and 4.0 lie on its top."""

DECK_Z = 4.0
"""Height of the bridge deck of `overpass_world` above the ground floor."""
DECK = (4.0, 5.9, 10.0, 9.3)
"""The deck's footprint (x0, y0, x1, y1); ramps join it to the ground at both x ends."""

GAP_WALL_X = 4.0
"""x of the wall that splits `gap_wall_world`; the gap is centred on y = 3 (a lattice line)."""

ALCOVE = (5.0, 2.35, 6.0, 3.35)
"""The alcove behind the east wall of `alcove_room` (x0, y0, x1, y1): 1 m wide, centred between
two lattice lines (2.5 and 3.2), so no lattice move fits into it; a manual point does."""
ALCOVE_POINT = (5.5, 2.85, 0.0)


def quad(p0, p1, p2, p3) -> np.ndarray:
    """Two triangles of the quad p0-p1-p2-p3 (corners in order around its boundary)."""
    return np.array([[p0, p1, p2], [p0, p2, p3]], dtype=np.float64)


def floor(x0: float, y0: float, x1: float, y1: float, z: float = 0.0) -> np.ndarray:
    """A level rectangle at height z."""
    return quad((x0, y0, z), (x1, y0, z), (x1, y1, z), (x0, y1, z))


def wall(x0: float, y0: float, x1: float, y1: float, z0: float, z1: float) -> np.ndarray:
    """A vertical quad standing on the segment (x0, y0)-(x1, y1), from z0 up to z1."""
    return quad((x0, y0, z0), (x1, y1, z0), (x1, y1, z1), (x0, y0, z1))


def box(x0: float, y0: float, x1: float, y1: float, z0: float, z1: float) -> np.ndarray:
    """The top and the four sides of an axis-aligned box (its bottom rests on a floor)."""
    return np.concatenate(
        [
            floor(x0, y0, x1, y1, z1),
            wall(x0, y0, x1, y0, z0, z1),
            wall(x1, y0, x1, y1, z0, z1),
            wall(x1, y1, x0, y1, z0, z1),
            wall(x0, y1, x0, y0, z0, z1),
        ]
    )


def ramp_x(x0: float, x1: float, y0: float, y1: float, z0: float, z1: float) -> np.ndarray:
    """A floor sloping along x: height z0 at x = x0, z1 at x = x1."""
    return quad((x0, y0, z0), (x1, y0, z1), (x1, y1, z1), (x0, y1, z0))


def walls_around(x0: float, y0: float, x1: float, y1: float, height: float = WALL_HEIGHT):
    """Four walls along the edges of a rectangle, standing on z = 0."""
    return np.concatenate(
        [
            wall(x0, y0, x1, y0, 0.0, height),
            wall(x1, y0, x1, y1, 0.0, height),
            wall(x1, y1, x0, y1, 0.0, height),
            wall(x0, y1, x0, y0, 0.0, height),
        ]
    )


def make_world(parts: list[np.ndarray], name: str, seed: tuple[float, float, float]) -> World:
    """A World of the given triangle blocks, with its test seed point in `meta["seed"]`."""
    return World(
        triangles=np.concatenate(parts),
        name=name,
        source=f"hand-made {name}",
        meta={"seed": [float(v) for v in seed]},
    )


def graph_of(result: LatticeResult) -> WaypointGraph:
    """The waypoint graph of a lattice built on a hand-made world: no places or regions; the
    build statistics in `meta["stats"]`."""
    return WaypointGraph(
        positions=result.positions,
        edge_source=result.edge_source,
        edge_target=result.edge_target,
        edge_kind=result.edge_kind,
        edge_direction=result.edge_direction,
        node_place=np.full(len(result.positions), -1, dtype=np.int16),
        place_names=[],
        regions={},
        meta={"stats": result.stats.as_dict()},
    )


def seeds_of(world: World) -> np.ndarray:
    """The (1, 3) seed array of a hand-made world."""
    return np.array([world.meta["seed"]], dtype=np.float64)


def room(size_x: float = ROOM_SIZE, size_y: float = ROOM_SIZE, origin=(0.0, 0.0)) -> World:
    """A floor at z = 0 with four walls; the seed is the centre."""
    ox, oy = origin
    return make_world(
        [floor(ox, oy, ox + size_x, oy + size_y), walls_around(ox, oy, ox + size_x, oy + size_y)],
        "room",
        (ox + size_x / 2, oy + size_y / 2, 0.0),
    )


def ledge_world() -> World:
    """A lower floor (x 0..6) next to a platform 1.5 m high (x 6..10), y 0..4: the face at
    x = 6 can be dropped down but not climbed. A lane north of a wall (y 4..6) holds a ramp
    (x 2..6) up to the platform, so the two floors form one strongly connected graph."""
    return make_world(
        [
            floor(0.0, 0.0, LEDGE_X, 4.0),  # lower floor
            floor(0.0, 4.0, 2.0, 6.0),  # foot of the ramp lane
            ramp_x(2.0, LEDGE_X, 4.0, 6.0, 0.0, LEDGE_Z),
            floor(LEDGE_X, 0.0, 10.0, 6.0, LEDGE_Z),  # platform top
            wall(LEDGE_X, 0.0, LEDGE_X, 4.0, 0.0, LEDGE_Z),  # the ledge face
            wall(2.0, 4.0, LEDGE_X, 4.0, 0.0, LEDGE_Z + WALL_HEIGHT),  # lane wall
        ],
        "ledge",
        (1.0, 1.0, 0.0),
    )


def jump_box_world() -> World:
    """An 8 x 8 m room with a 0.9 m box in it (see BOX and BOX_Z)."""
    return make_world(
        [floor(0.0, 0.0, 8.0, 8.0), walls_around(0.0, 0.0, 8.0, 8.0), box(*BOX, 0.0, BOX_Z)],
        "jump box",
        (0.5, 0.5, 0.0),
    )


def overpass_world() -> World:
    """A ground floor (x -6..20, y 0..15) and a bridge deck 4 m above it (see DECK), joined to
    the ground by a ramp at each end (slope 1:2); the ground runs on under the deck."""
    x0, y0, x1, y1 = DECK
    return make_world(
        [
            floor(-6.0, 0.0, 20.0, 15.0),
            floor(x0, y0, x1, y1, DECK_Z),
            ramp_x(x0 - 2 * DECK_Z, x0, y0, y1, 0.0, DECK_Z),
            ramp_x(x1, x1 + 2 * DECK_Z, y0, y1, DECK_Z, 0.0),
        ],
        "overpass",
        (0.0, 2.0, 0.0),
    )


CLIFF_Z = 6.0
"""Height of the cliff world's plateau: a 315 u fall, deeper than the safe 210 u."""

CLIFF = (8.0, 2.0, 14.0, 6.0)
"""The plateau's x0, y0, x1, y1 (metres)."""


def cliff_world() -> World:
    """A ground floor (x -14..20, y 0..10) and a plateau `CLIFF_Z` above it (see CLIFF), reached
    by a ramp (slope 1:2) from the west; its other sides are cliffs down to the ground."""
    x0, y0, x1, y1 = CLIFF
    return make_world(
        [
            floor(-14.0, 0.0, 20.0, 10.0),
            floor(x0, y0, x1, y1, CLIFF_Z),
            ramp_x(x0 - 2 * CLIFF_Z, x0, y0, y1, 0.0, CLIFF_Z),
        ],
        "cliff",
        (0.0, 8.0, 0.0),
    )


def gap_wall_world(gap: float) -> World:
    """An 8 x 6 m room split at x = 4 by a wall with a gap `gap` m wide centred on y = 3."""
    lo, hi = 3.0 - gap / 2, 3.0 + gap / 2
    return make_world(
        [
            floor(0.0, 0.0, 8.0, 6.0),
            walls_around(0.0, 0.0, 8.0, 6.0),
            wall(GAP_WALL_X, 0.0, GAP_WALL_X, lo, 0.0, WALL_HEIGHT),
            wall(GAP_WALL_X, hi, GAP_WALL_X, 6.0, 0.0, WALL_HEIGHT),
        ],
        f"gap {gap} m",
        (2.0, 3.0, 0.0),
    )


def alcove_room() -> World:
    """The 5 x 5 m room with a 1 m wide, 1 m deep alcove in its east wall (see ALCOVE)."""
    x0, y0, x1, y1 = ALCOVE
    return make_world(
        [
            floor(0.0, 0.0, ROOM_SIZE, ROOM_SIZE),
            floor(x0, y0, x1, y1),
            wall(0.0, 0.0, ROOM_SIZE, 0.0, 0.0, WALL_HEIGHT),
            wall(ROOM_SIZE, 0.0, ROOM_SIZE, y0, 0.0, WALL_HEIGHT),
            wall(ROOM_SIZE, y1, ROOM_SIZE, ROOM_SIZE, 0.0, WALL_HEIGHT),
            wall(ROOM_SIZE, ROOM_SIZE, 0.0, ROOM_SIZE, 0.0, WALL_HEIGHT),
            wall(0.0, ROOM_SIZE, 0.0, 0.0, 0.0, WALL_HEIGHT),
            wall(x0, y0, x1, y0, 0.0, WALL_HEIGHT),
            wall(x1, y0, x1, y1, 0.0, WALL_HEIGHT),
            wall(x1, y1, x0, y1, 0.0, WALL_HEIGHT),
        ],
        "alcove room",
        (ROOM_SIZE / 2, ROOM_SIZE / 2, 0.0),
    )


FIXTURE_ROOM = (-21.35, 7.45, 7.35, 16.55)
"""Floor (x0, y0, x1, y1) of `fixture_room`: it holds every player position of the generated
ESTA match of tests/esta_fixtures.py (x -19.05..5.0 m, y 8.45..15.24 m, z 0..0.38 m). Its walls
stand 0.35 m beyond the outermost lattice lines of the seed (-7, 12), never on one."""


def fixture_room() -> World:
    """A 28.7 x 9.1 m walled room under the ESTA fixture's players (a map-sized user mesh)."""
    x0, y0, x1, y1 = FIXTURE_ROOM
    return make_world(
        [floor(x0, y0, x1, y1), walls_around(x0, y0, x1, y1)], "fixture room", (-7.0, 12.0, 0.0)
    )


def write_awmh(world: World, path, version: int = 1) -> None:
    """The world as awpy 3's `.mesh` (little-endian `AWMH`, version, vertex and triangle
    counts as uint32, float32 vertices in Hammer units, uint32 corner indices), written by
    hand from the format awpy documents: a fixture in the real layout."""
    import struct

    from decoy_cli.csgo import HAMMER_TO_M

    vertices, indices = world.vertices_and_indices()
    header = struct.pack("<4s3I", b"AWMH", version, len(vertices), len(indices))
    body = (vertices / HAMMER_TO_M).astype("<f4").tobytes() + indices.astype("<u4").tobytes()
    path.write_bytes(header + body)
