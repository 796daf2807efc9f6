"""The built-in de_dust2 nav mesh and nav world, and pybullet rays and capsules on it."""

from __future__ import annotations

from collections.abc import Iterator

import numpy as np
import pytest

from decoy_cli.csgo import EYE_HEIGHT_M, HAMMER_TO_M, PLAYER_HEIGHT_M, PLAYER_RADIUS_M
from decoy_cli.errors import WorldError
from decoy_cli.waypoints.build import builtin_graph, default_seeds
from decoy_cli.world import nav_geometry, navmesh
from decoy_cli.world.nav_geometry import box_triangles
from decoy_cli.world.navmesh import REGIONS, NavMesh, load_navmesh, nav_world
from decoy_cli.world.physics import PhysicsWorld
from decoy_cli.world.world import World


@pytest.fixture(scope="module")
def nav() -> NavMesh:
    return load_navmesh()


@pytest.fixture(scope="module")
def world() -> World:
    return nav_world()


@pytest.fixture(scope="module")
def physics(world: World) -> Iterator[PhysicsWorld]:
    with PhysicsWorld(world) as loaded:
        yield loaded


UP = np.array([0.0, 0.0, 1.0])


def largest_area(nav: NavMesh, place: str) -> int:
    idx = np.nonzero(nav.place == place)[0]
    return int(idx[np.argmax((nav.x_max - nav.x_min)[idx] * (nav.y_max - nav.y_min)[idx])])


def centre_m(nav: NavMesh, area: int) -> np.ndarray:
    """Centre of an area's rectangle on its floor, metres. The floor quad is split along the
    diagonal through the two known corners, so the triangle surface there lies at their mean."""
    return (
        np.array(
            [
                (nav.x_min[area] + nav.x_max[area]) / 2,
                (nav.y_min[area] + nav.y_max[area]) / 2,
                (nav.z_at_min[area] + nav.z_at_max[area]) / 2,
            ]
        )
        * HAMMER_TO_M
    )


# ---- the nav mesh ------------------------------------------------------------------------------


def test_load_navmesh(nav: NavMesh) -> None:
    assert nav.num_areas == 1118
    assert len(nav.connections) == 4214
    assert len(np.unique(nav.area_id)) == nav.num_areas
    assert nav.connections.min() >= 0 and nav.connections.max() < nav.num_areas
    assert {"TSpawn", "CTSpawn", "BombsiteA", "BombsiteB"} <= set(nav.places)
    assert {p for r in REGIONS for p in nav.regions[r]} <= set(nav.places)
    assert np.all(nav.x_min < nav.x_max) and np.all(nav.y_min < nav.y_max)
    assert nav.radar == {"pos_x": -2476.0, "pos_y": 3239.0, "scale": 4.4}


def test_unknown_builtin_map() -> None:
    with pytest.raises(WorldError, match="no built-in map 'de_cache'"):
        load_navmesh("de_cache")


def seam_mismatch(nav: NavMesh, contacts, zx: np.ndarray, zy: np.ndarray) -> np.ndarray:
    """Largest height difference (Hammer units) of the two floors at the ends of each contact."""
    out = np.zeros(len(contacts))
    for k, c in enumerate(contacts):
        for t in (0.0, 1.0):
            x, y = nav_geometry._edge_point(c, t)
            a = nav_geometry._height(nav, zx, zy, c.a, x, y)
            b = nav_geometry._height(nav, zx, zy, c.b, x, y)
            out[k] = max(out[k], abs(a - b))
    return out


def test_fit_corner_heights_closes_level_seams(nav: NavMesh) -> None:
    """Before the fit (each dropped corner at the mean of the two known ones) seams between
    level neighbours show steps (p90 about 11 u); after it they mostly meet."""
    contacts = nav_geometry._find_contacts(nav)
    assert len(contacts) > 2000
    mean = (nav.z_at_min + nav.z_at_max) / 2
    before = seam_mismatch(nav, contacts, mean, mean)
    zx, zy = nav_geometry.fit_corner_heights(nav, contacts)
    after = seam_mismatch(nav, contacts, zx, zy)
    level = before <= nav_geometry.SEAM_MATCH_U
    assert level.sum() > 1900
    med_b, p90_b = np.percentile(before[level], [50, 90])
    med_a, p90_a = np.percentile(after[level], [50, 90])
    assert p90_b > 8.0  # the problem the fit exists for
    assert med_a < 0.5 * med_b and p90_a < 0.5 * p90_b
    assert p90_a < 5.0
    # the fit leaves the known corners alone and keeps the fitted ones sensible
    assert np.all(np.isfinite(zx)) and np.all(np.isfinite(zy))
    low = np.minimum(nav.z_at_min, nav.z_at_max).min()
    high = np.maximum(nav.z_at_min, nav.z_at_max).max()
    assert low - 10 <= min(zx.min(), zy.min()) and max(zx.max(), zy.max()) <= high + 10


def test_nav_world_shape_and_bounds(nav: NavMesh, world: World) -> None:
    bare = nav_world(patches=())
    assert 9_000 <= bare.num_triangles <= 12_000
    patches = len(navmesh.load_patches())
    per_box = len(box_triangles(0, 0, 1, 1, 1, 0))
    assert world.num_triangles == bare.num_triangles + per_box * patches
    assert np.all(np.isfinite(world.triangles))
    low, high = world.bounds
    push = (nav_geometry.WALL_PUSH_U + nav_geometry.TOUCH_TOL_U) * HAMMER_TO_M
    assert low[0] >= nav.x_min.min() * HAMMER_TO_M - push
    assert high[0] <= nav.x_max.max() * HAMMER_TO_M + push
    assert low[1] >= nav.y_min.min() * HAMMER_TO_M - push
    assert high[1] <= nav.y_max.max() * HAMMER_TO_M + push
    z_low = min(nav.z_at_min.min(), nav.z_at_max.min()) * HAMMER_TO_M
    z_high = max(nav.z_at_min.max(), nav.z_at_max.max()) * HAMMER_TO_M
    assert low[2] >= z_low - 0.5
    assert high[2] <= z_high + nav_geometry.WALL_HEIGHT_U * HAMMER_TO_M + 0.5
    # inside the radar picture (1024 px at `scale` units per pixel from the top-left corner)
    radar = nav.radar
    side = 1024 * radar["scale"] * HAMMER_TO_M
    x0, y1 = radar["pos_x"] * HAMMER_TO_M, radar["pos_y"] * HAMMER_TO_M
    assert x0 <= low[0] and high[0] <= x0 + side
    assert y1 - side <= low[1] and high[1] <= y1
    assert world.meta == {"kind": "navmesh", "areas": 1118, "patches": patches}


def test_shipped_graph_was_built_from_this_world(world: World) -> None:
    """Cheap guard: a change to the nav world changes its fingerprint (the CLI test rebuilds)."""
    assert builtin_graph().meta["world"]["sha256"] == world.fingerprint()


# ---- area_of -----------------------------------------------------------------------------------


@pytest.mark.parametrize("place", ["TSpawn", "CTSpawn", "BombsiteA", "BombsiteB"])
def test_area_of_known_spots(nav: NavMesh, place: str) -> None:
    area = largest_area(nav, place)
    found = nav.area_of(centre_m(nav, area) + 0.1 * UP)
    assert found.tolist() == [area]
    assert nav.place[found[0]] == place


def test_area_of_spawn_seeds(nav: NavMesh) -> None:
    found = nav.area_of(default_seeds(nav))
    assert nav.place[found].tolist() == ["TSpawn", "CTSpawn"]


def test_area_of_every_centre_and_off_map(nav: NavMesh) -> None:
    centres = np.array([centre_m(nav, a) for a in range(nav.num_areas)])
    np.testing.assert_array_equal(nav.area_of(centres), np.arange(nav.num_areas))
    assert nav.area_of(np.array([[500.0, 500.0, 0.0], [0.0, 0.0, 80.0]])).tolist() == [-1, -1]


def test_area_of_two_floors(nav: NavMesh) -> None:
    """Where an upper area lies over a lower one, the point's height picks the floor."""
    cz = (nav.z_at_min + nav.z_at_max) / 2
    x0, x1, y0, y1 = nav.x_min, nav.x_max, nav.y_min, nav.y_max
    overlap_x = np.minimum(x1[:, None], x1) - np.maximum(x0[:, None], x0)
    overlap_y = np.minimum(y1[:, None], y1) - np.maximum(y0[:, None], y0)
    upper, lower = np.nonzero((overlap_x > 40) & (overlap_y > 40) & (cz[:, None] - cz > 150))
    assert len(upper) >= 5  # dust2 has a few (ExtendedA over CT spawn)
    for a, b in zip(upper, lower, strict=True):
        x = (max(nav.x_min[a], nav.x_min[b]) + min(nav.x_max[a], nav.x_max[b])) / 2
        y = (max(nav.y_min[a], nav.y_min[b]) + min(nav.y_max[a], nav.y_max[b])) / 2
        points = np.array([[x, y, cz[a] + 5], [x, y, cz[b] + 5]]) * HAMMER_TO_M
        found = nav.area_of(points)
        assert cz[found[0]] > cz[found[1]] + 150


# ---- pybullet on the nav world -----------------------------------------------------------------


def test_ray_down_hits_each_area_floor(nav: NavMesh) -> None:
    """On the bare nav world (learned patches stand on some areas' floors)."""
    centres = np.array([centre_m(nav, a) for a in range(nav.num_areas)])
    with PhysicsWorld(nav_world(patches=())) as physics:
        z, normal_z = physics.first_floor_below(centres + 0.5 * UP, 1.0)
        fraction, _ = physics.ray_test(centres + 0.5 * UP, centres + 0.2 * UP)
    assert np.all(np.isfinite(z))
    error = np.abs(z - centres[:, 2])
    assert np.sum(error < 1e-3) >= nav.num_areas - 5  # a few centres lie under another floor
    assert np.all(normal_z > 0.5)
    # a ray that ends above the floor misses
    assert np.mean(np.isinf(fraction)) > 0.99


def test_ray_batches_beyond_pybullet_limit(nav: NavMesh, physics: PhysicsWorld) -> None:
    """More rays than one rayTestBatch call takes (16,384): every ray still gets its answer."""
    centres = np.array([centre_m(nav, a) for a in range(nav.num_areas)])
    starts = np.tile(centres + 0.5 * UP, (16, 1))
    assert len(starts) > 16_384
    z, _ = physics.first_floor_below(starts, 1.0)
    single, _ = physics.first_floor_below(centres + 0.5 * UP, 1.0)
    np.testing.assert_array_equal(z, np.tile(single, 16))


def wall_triangles(world: World, count: int) -> tuple[np.ndarray, np.ndarray]:
    """Centroids and horizontal unit normals of `count` full-height walls of the world."""
    tri = world.triangles
    normal = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    normal /= np.linalg.norm(normal, axis=1, keepdims=True)
    height = np.ptp(tri[:, :, 2], axis=1)
    walls = np.nonzero(
        (np.abs(normal[:, 2]) < 1e-6) & (height >= nav_geometry.WALL_HEIGHT_U * HAMMER_TO_M - 1e-6)
    )[0]
    assert len(walls) > 1000
    pick = np.random.default_rng(11).choice(walls, size=count, replace=False)
    return tri[pick].mean(axis=1), normal[pick]


def test_line_of_sight_open_and_through_walls(nav: NavMesh, world, physics) -> None:
    starts, ends = [], []
    for place in ("TSpawn", "CTSpawn", "BombsiteA", "BombsiteB"):
        a = largest_area(nav, place)
        inset = 30.0
        corners = np.array(
            [
                [nav.x_min[a] + inset, nav.y_min[a] + inset],
                [nav.x_max[a] - inset, nav.y_max[a] - inset],
            ]
        )
        z = centre_m(nav, a)[2] + EYE_HEIGHT_M
        starts.append([*(corners[0] * HAMMER_TO_M), z])
        ends.append([*(corners[1] * HAMMER_TO_M), z])
    assert physics.line_of_sight(np.array(starts), np.array(ends)).all()

    centre, normal = wall_triangles(world, 100)
    assert not physics.line_of_sight(centre + 0.3 * normal, centre - 0.3 * normal).any()
    assert not physics.line_of_sight(centre - 0.3 * normal, centre + 0.3 * normal).any()


def test_capsules_blocked_in_walls_free_on_open_floor(nav: NavMesh, world, physics) -> None:
    radius, height = PLAYER_RADIUS_M, PLAYER_HEIGHT_M
    centre, _ = wall_triangles(world, 100)
    floors = [centre_m(nav, largest_area(nav, p)) for p in ("TSpawn", "CTSpawn", "BombsiteB")]
    open_floor = np.array(floors) + (0.05 + height / 2) * UP
    # more capsules than the pool holds (1,024), the two kinds interleaved
    points = np.concatenate([centre, open_floor] * 11)
    expect = np.concatenate([np.ones(len(centre), bool), np.zeros(len(open_floor), bool)] * 11)
    assert len(points) > 1024
    np.testing.assert_array_equal(physics.capsules_blocked(points, radius, height), expect)
    # sunk into the floor, the same open-floor capsules are blocked
    sunk = open_floor - 0.3 * UP
    assert physics.capsules_blocked(sunk, radius, height).all()


MID_STEP = (-5.9, 25.75)
"""On the step in front of the mid boxes (metres), where real T players stand at z -1.314 m."""


def test_patch_adds_the_mid_step(physics: PhysicsWorld) -> None:
    z, normal_z = physics.first_floor_below(np.array([[*MID_STEP, 0.0]]), 3.0)
    np.testing.assert_allclose(z, -69 * HAMMER_TO_M, atol=1e-6)
    assert normal_z[0] > 0.99
    box = navmesh.load_patches()
    assert box.shape[1] == 6 and len(box) > 1  # learned from the real data (world_patches.csv)
    assert (box[:, 4] > box[:, 5]).all()  # the top is above the bottom


def test_a_ledge_face_ends_at_the_higher_floor(physics: PhysicsWorld) -> None:
    """The mid floor's north side faces the boxes' nav area 50 u away: the face ends at the
    boxes' top instead of standing 3.5 m tall, so a jump from the step onto the boxes is open
    (blocked at knee height by the face, clear above the top)."""
    box_top = -0.545
    start, end = np.array([MID_STEP[0], 25.75]), np.array([MID_STEP[0], 26.5])
    knee = np.array([[*start, box_top - 0.3]]), np.array([[*end, box_top - 0.3]])
    above = np.array([[*start, box_top + 0.4]]), np.array([[*end, box_top + 0.4]])
    assert not physics.line_of_sight(*knee)[0]
    assert physics.line_of_sight(*above)[0]


def test_mid_boxes_are_reached_from_mid_by_the_step() -> None:
    """Mid floor -> step (jump) -> boxes (jump): a few metres, not the 28 m detour round the
    back that the graph had without the step."""
    graph = builtin_graph()
    floor, box = graph.nearest(np.array([[-6.44, 24.39, -2.4], [-6.09, 26.49, -0.54]]))[0]
    path = graph.shortest_path(int(floor), int(box))
    length = np.linalg.norm(np.diff(graph.positions[path], axis=0), axis=1).sum()
    assert length < 4.0


def test_pybullet_imports_without_its_banner() -> None:
    """pybullet prints "pybullet build time: ..." from C at import; users must not see it."""
    import subprocess
    import sys

    code = "from decoy_cli.world.physics import load_pybullet; load_pybullet(); print('ok')"
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert done.stdout == "ok\n"
    assert "build time" not in done.stderr


def hand_nav(*areas: tuple[float, float, float, float, float]) -> NavMesh:
    """A nav mesh of flat areas (x_min, y_min, x_max, y_max, z), Hammer units, unlinked."""
    rows = np.array(areas, dtype=np.float64)
    return NavMesh(
        area_id=np.arange(1, len(rows) + 1),
        place=np.array(["Hand"] * len(rows)),
        x_min=rows[:, 0],
        y_min=rows[:, 1],
        x_max=rows[:, 2],
        y_max=rows[:, 3],
        z_at_min=rows[:, 4],
        z_at_max=rows[:, 4],
        connections=np.zeros((0, 2), dtype=np.int64),
        radar={},
        regions={},
    )


def test_open_stretches_wall_a_side_over_a_lower_floor_reaching_under_it() -> None:
    """A platform (area 0) with a lower floor reaching under its east side (area 1) and another
    lower floor 64 u beyond its north side (area 2): the north side is a ledge onto area 2, the
    east side a full wall (what benchmarks/studies/ledge_candidates.py measures: issue 34's
    rule)."""
    nav = hand_nav(
        (0.0, 0.0, 200.0, 200.0, 200.0),
        (150.0, 0.0, 400.0, 200.0, 0.0),
        (0.0, 264.0, 200.0, 400.0, 50.0),
    )
    stretches = {
        (side.axis, side.sign): part.other
        for side, part in nav_geometry.open_stretches(nav)
        if side.area == 0
    }
    assert stretches[(1, 1.0)] == 2  # north: a ledge onto the floor beyond
    assert stretches[(0, 1.0)] == -1  # east: walled, though area 1 lies below
    assert stretches[(0, -1.0)] == -1 and stretches[(1, -1.0)] == -1
