"""From a world to a saved `WaypointGraph`: seeds, the lattice builder, places and regions.

The built-in map's graph ships in the package (`builtin_graph()`); `build_graph()` rebuilds it,
or builds one for a user's own mesh of the same map (places and regions always come from the
map's nav mesh, which names the spots players talk about: TSpawn, BombsiteA, LongA, ...).
"""

from __future__ import annotations

import csv
import io
from dataclasses import asdict
from functools import cache
from pathlib import Path
from typing import Literal

import numpy as np

from decoy_cli.csgo import HAMMER_TO_M, MAP_NAMES
from decoy_cli.errors import GraphError
from decoy_cli.reading import open_regular
from decoy_cli.waypoints.graph import FORMAT_VERSION, WaypointGraph
from decoy_cli.waypoints.lattice import LatticeParams, LatticeResult, Progress, build_lattice
from decoy_cli.world.nav_climbs import world_climbs
from decoy_cli.world.nav_polygons import POLYGON_NAV_KIND
from decoy_cli.world.navmesh import BUILTIN_MAP, NavMesh, asset_dir, load_navmesh, nav_world
from decoy_cli.world.physics import PhysicsWorld
from decoy_cli.world.world import World

GRAPH_FILE = "waypoints.npz"
CS2_GRAPH_FILE = "cs2_waypoints.npz"
"""A map's graph on its CS2 world (built with `--nav` from CS2's nav mesh; it carries the world)."""
GameWorld = Literal["csgo", "cs2"]


def canonical_map(name: str) -> str:
    """'mirage' or 'de_mirage' -> 'de_mirage'; a GraphError for maps the project has no data for."""
    key = name.lower()
    for candidate in (key, f"de_{key}"):
        if candidate in MAP_NAMES:
            return candidate
    short = ", ".join(m.removeprefix("de_") for m in MAP_NAMES)
    raise GraphError(f"unknown map {name!r}; this decoy knows: {short}")


def default_seeds(nav: NavMesh) -> np.ndarray:
    """The centres of the largest T-spawn and CT-spawn nav areas, metres: every playable spot
    is reachable from a spawn."""
    seeds = []
    for region in ("t_spawn", "ct_spawn"):
        idx = np.nonzero(np.isin(nav.place, nav.regions[region]))[0]
        area = idx[np.argmax((nav.x_max - nav.x_min)[idx] * (nav.y_max - nav.y_min)[idx])]
        seeds.append(
            [
                (nav.x_min[area] + nav.x_max[area]) / 2,
                (nav.y_min[area] + nav.y_max[area]) / 2,
                (nav.z_at_min[area] + nav.z_at_max[area]) / 2,
            ]
        )
    return np.asarray(seeds) * HAMMER_TO_M


def read_manual_waypoints(path: str | Path) -> np.ndarray:
    """Manual waypoints from a CSV file with a header `x,y,z` (metres, Source axes)."""
    path = Path(path)
    if not path.exists():
        raise GraphError(f"cannot read manual waypoints {path}: no such file")
    try:
        with io.TextIOWrapper(open_regular(path, GraphError), newline="") as f:
            rows = list(csv.DictReader(f))
    except OSError as error:
        raise GraphError(f"cannot read manual waypoints {path}: {error.strerror}") from None
    except (UnicodeDecodeError, csv.Error) as error:
        raise GraphError(f"{path}: not a CSV file ({error})") from None
    points = []
    for line, row in enumerate(rows, start=2):
        try:
            points.append([float(row["x"]), float(row["y"]), float(row["z"])])
        except (KeyError, TypeError, ValueError):
            raise GraphError(
                f"{path}, line {line}: expected numbers in columns x, y, z (metres)"
            ) from None
    result = np.asarray(points, dtype=np.float64).reshape(-1, 3)
    if not np.all(np.isfinite(result)):
        raise GraphError(f"{path}: a manual waypoint has a NaN or infinite coordinate")
    return result


def build_graph(
    world: World,
    map_name: str = BUILTIN_MAP,
    seeds: np.ndarray | None = None,
    params: LatticeParams = LatticeParams(),
    manual: np.ndarray | None = None,
    progress: Progress = lambda stage, done, total: None,
) -> tuple[WaypointGraph, LatticeResult]:
    """Build the waypoint graph of a world of a known map; deterministic for equal inputs."""
    nav = load_navmesh(map_name)
    seed_points = default_seeds(nav) if seeds is None else np.asarray(seeds, dtype=np.float64)
    with PhysicsWorld(world) as physics:
        climbs = world_climbs(world)
        result = build_lattice(physics, seed_points, params, manual, progress, nav.ladders, climbs)
    places = nav.places
    place_index = {name: k for k, name in enumerate(places)}
    area = nav.area_of(result.positions)
    node_place = np.array(
        [place_index.get(str(nav.place[a]), -1) if a >= 0 else -1 for a in area], dtype=np.int16
    )
    regions = {
        region: np.nonzero(np.isin(node_place, [place_index[p] for p in region_places]))[0]
        for region, region_places in nav.regions.items()
    }
    carried = world.meta.get("kind") == POLYGON_NAV_KIND  # no package holds it: the graph does
    stats = result.stats.as_dict()
    stats.pop("seconds")  # timings vary run to run; the file must not
    graph = WaypointGraph(
        positions=result.positions,
        edge_source=result.edge_source,
        edge_target=result.edge_target,
        edge_kind=result.edge_kind,
        edge_direction=result.edge_direction,
        node_place=node_place,
        place_names=places,
        regions=regions,
        meta={
            "format_version": FORMAT_VERSION,
            "map": map_name,
            "world": {
                "name": world.name,
                "source": world.source,
                "triangles": world.num_triangles,
                "sha256": world.fingerprint(),
                **({"kind": POLYGON_NAV_KIND} if carried else {}),
            },
            "params": asdict(params),
            "seeds_m": np.round(seed_points, 6).tolist(),
            "manual_waypoints": 0 if manual is None else len(manual),
            **({"patches": world.meta["patch_boxes"]} if "patch_boxes" in world.meta else {}),
            **({"climbs_joined": result.climbs_joined} if climbs is not None else {}),
            "stats": stats,
        },
        world_triangles=world.triangles if carried else None,
    )
    return graph, result


@cache
def builtin_graph(map_name: str = BUILTIN_MAP, world: GameWorld = "csgo") -> WaypointGraph:
    """The waypoint graph shipped with the package for a built-in map, on its CS:GO world or
    on its CS2 world (which the graph carries), cached per process; a GraphError when the
    package ships no CS2 world of the map."""
    folder = asset_dir(canonical_map(map_name))
    if world == "csgo":
        return WaypointGraph.load(folder / GRAPH_FILE)
    if not (folder / CS2_GRAPH_FILE).is_file():
        raise GraphError(
            f"decoy ships no CS2 world of {map_name}: build one with `decoy build-waypoints "
            "--nav FILE` and give it with --graph"
        )
    return WaypointGraph.load(folder / CS2_GRAPH_FILE)


def chosen_graph(map_name: str, world: GameWorld, graph_file: Path | None) -> WaypointGraph:
    """The graph a command replays on: the user's `--graph` file, which brings its own world,
    else the map's shipped graph on `world`; a GraphError when both a file and CS2's world
    are asked for."""
    if graph_file is None:
        return builtin_graph(map_name, world)
    if world != "csgo":
        raise GraphError("--graph brings its own world: leave out --world")
    return WaypointGraph.load(graph_file)


def graph_world(graph: WaypointGraph) -> World:
    """The world a graph was built on: the one it carries (a CS2 nav world), else the built-in
    nav world of its map with the map's shipped patches, or with the patches recorded in the
    graph (built with learned ones)."""
    map_name = str(graph.meta.get("map", "")) or BUILTIN_MAP
    if graph.world_triangles is not None:
        described = graph.meta.get("world", {})
        world = World(
            triangles=graph.world_triangles,
            name=str(described.get("name", map_name)),
            source=str(described.get("source", "the world the graph carries")),
            meta={"kind": POLYGON_NAV_KIND},
        )
        if world.fingerprint() != described.get("sha256"):
            raise GraphError("the world this graph carries does not match its own fingerprint")
        return world
    boxes = graph.meta.get("patches")
    if boxes is None:
        return nav_world(map_name)
    return nav_world(map_name, tuple(tuple(float(v) for v in box) for box in boxes))
