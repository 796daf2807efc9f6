"""The waypoint graph: nodes on walkable floors, directed edges along the 8 compass directions.

A `WaypointGraph` is plain arrays (positions in metres, edges as source/target/kind/direction),
so it saves to one versioned `.npz` file, loads in milliseconds, and feeds numpy, scipy and the
simulator directly. Queries:

* `nearest(points)`: floor-aware nearest waypoint, vectorised. The search runs in a space whose
  z axis is stretched, and a candidate must lie within a vertical band around the query, so a
  player on the upper floor of a two-floor spot never snaps to the floor below (or above).
* `shortest_path(a, b)` / `path_lengths(a)`: Dijkstra on edge costs (`edge_cost`: length plus
  time in the air) over the directed graph.

Compass directions are numbered clockwise from north (N = +y, E = +x): 0 N, 1 NE, 2 E, 3 SE,
4 S, 5 SW, 6 W, 7 NW. These are also the paper's 8 move actions; action 8 is STOP.
"""

from __future__ import annotations

import io
import json
import zipfile
from dataclasses import dataclass, field
from enum import IntEnum
from functools import cached_property
from pathlib import Path
from typing import Any

import numpy as np
from scipy.sparse import csr_matrix
from scipy.sparse.csgraph import dijkstra
from scipy.spatial import cKDTree

from decoy_cli.csgo import (
    GRAVITY_M_S2,
    HAMMER_TO_M,
    JUMP_SPEED_M_S,
    LADDER_SPEED_M_S,
    SAFE_DROP_M,
)
from decoy_cli.errors import GraphError
from decoy_cli.files import write_atomic
from decoy_cli.weapons import KNIFE_SPEED

FORMAT_VERSION = 1
"""Version of the graph file; bump when the arrays or their meaning change."""

DIRECTION_NAMES = ("N", "NE", "E", "SE", "S", "SW", "W", "NW")
DIRECTION_VECTORS = np.array(
    [(0, 1), (1, 1), (1, 0), (1, -1), (0, -1), (-1, -1), (-1, 0), (-1, 1)], dtype=np.int64
)
"""Lattice offsets (di, dj) of each compass direction, index = direction number."""
STOP_ACTION = 8


class EdgeKind(IntEnum):
    """How an agent crosses an edge."""

    WALK = 0  # level or gently sloped floor
    STEP = 1  # a ledge up to the step height, walked without jumping
    JUMP = 2  # a ledge above the step height, reached with a (crouch-)jump
    DROP = 3  # a one-way drop to a lower floor
    LADDER = 4  # up or down a ladder of the nav mesh, at the climbing speed


LADDER_REACH_M = 0.75
"""How far across the floor from the line between a ladder's two waypoints a climbing player may
be (half a player's width plus about a lattice spacing: the builder puts a ladder's waypoints
beside its foot and past its lip): chosen, not measured."""


def _to_segment_2d(points: np.ndarray, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """(M,) distance of each 2-D point to the segment from a to b."""
    ab = b - a
    length2 = float(ab @ ab)
    t = np.clip((points - a) @ ab / length2, 0.0, 1.0) if length2 > 0 else np.zeros(len(points))
    return np.linalg.norm(points - (a + t[:, None] * ab), axis=1)


# Vertical band for the floor-aware lookup: how far a waypoint may lie above or below the query.
# Feet sit on the floor, so the band is tight above: a waypoint more than a step (plus a ramp's
# rise between lattice points) above the feet is on a box or ledge the player is not on. It is
# loose below: a jumping or falling player is above its floor. Floors of a two-floor spot are at
# least a player height (1.37 m) apart. (Measured on the 385 real T rounds: with 0.75 m above,
# players at the foot of boxes snapped onto the box top.)
SNAP_MAX_ABOVE_M = 0.4
SNAP_MAX_BELOW_M = 1.25
AIRBORNE_M = 0.4
"""Height above the world's floor from which a position counts as in the air (a jump or a
fall; a crouch-jump rises 1.2 m, players on the nav world's floors stand within centimetres)."""


def in_the_air(
    z: np.ndarray, floor_z: np.ndarray, vertical_speed: np.ndarray | None = None
) -> np.ndarray:
    """Which positions are in the air: more than `AIRBORNE_M` above the world's floor (NaN:
    unknown, not in the air), or with a known vertical speed that is not zero (awpy's velocityZ,
    m/s: the Source engine keeps none on the ground). The one rule of the replay, `decoy snap`
    and `--check-esta`."""
    with np.errstate(invalid="ignore"):
        airborne = np.asarray(z, dtype=np.float64) - floor_z > AIRBORNE_M
    if vertical_speed is not None:
        speed = np.asarray(vertical_speed, dtype=np.float64)
        airborne |= np.isfinite(speed) & (speed != 0)
    return airborne


RUN_SPEED_M_S = KNIFE_SPEED * HAMMER_TO_M
"""The speed that turns seconds in the air into metres of path cost: running with the knife."""

_Z_STRETCH = 4.0
_CANDIDATES = 12


@dataclass
class WaypointGraph:
    """Waypoints and directed edges, in metres; see the module docstring."""

    positions: np.ndarray  # (N, 3) float64
    edge_source: np.ndarray  # (E,) int32
    edge_target: np.ndarray  # (E,) int32
    edge_kind: np.ndarray  # (E,) uint8, EdgeKind
    edge_direction: np.ndarray  # (E,) uint8, compass direction 0..7
    node_place: np.ndarray  # (N,) int16 index into place_names, -1 = none
    place_names: list[str]
    regions: dict[str, np.ndarray]  # region name -> sorted node indices
    meta: dict[str, Any] = field(default_factory=dict)
    world_triangles: np.ndarray | None = None
    """(T, 3, 3) metres: the world the graph was built on, carried in the file when it is not
    a built-in one (a CS2 nav world), so the graph replays on it wherever it goes."""

    # ---- basic properties -------------------------------------------------------------------

    @property
    def world_source(self) -> str:
        """Where the world the graph was built on comes from, in words."""
        described = self.meta.get("world", {})
        return str(described.get("source", "")) if isinstance(described, dict) else ""

    @property
    def num_nodes(self) -> int:
        return len(self.positions)

    @property
    def num_edges(self) -> int:
        return len(self.edge_source)

    @cached_property
    def edge_length(self) -> np.ndarray:
        """3-D length of every edge in metres."""
        delta = self.positions[self.edge_target] - self.positions[self.edge_source]
        return np.linalg.norm(delta, axis=1)

    @cached_property
    def edge_rise_m(self) -> np.ndarray:
        """(E,) height of each edge's end above its start, metres (negative going down)."""
        return self.positions[self.edge_target, 2] - self.positions[self.edge_source, 2]

    @cached_property
    def fall_m(self) -> np.ndarray:
        """(E,) depth of each drop edge deeper than the safe fall, metres; 0 for every other
        edge. An agent that takes such an edge lands with fall damage (the simulator's rule)."""
        depth = -self.edge_rise_m
        damaging = (self.edge_kind == EdgeKind.DROP) & (depth > SAFE_DROP_M)
        return np.where(damaging, depth, 0.0)

    @cached_property
    def edge_air_s(self) -> np.ndarray:
        """(E,) seconds of each edge spent in the air, under sv_gravity: a jump up rises straight
        onto the edge's height (at least the jump's take-off speed) before it moves on; off a
        ledge (a drop, a jump down) the run goes on while the agent falls, so the edge takes
        its fall and no run (`edge_run_m`)."""
        dz = self.edge_rise_m
        up = (self.edge_kind == EdgeKind.JUMP) & (dz > 0)
        rise = np.maximum(dz, 0.0)
        take_off = np.maximum(JUMP_SPEED_M_S, np.sqrt(2 * GRAVITY_M_S2 * rise))
        rise_s = (take_off - np.sqrt(np.maximum(take_off**2 - 2 * GRAVITY_M_S2 * rise, 0.0))) / (
            GRAVITY_M_S2
        )
        fall_s = np.sqrt(2 * np.maximum(-dz, 0.0) / GRAVITY_M_S2)
        return np.where(up, rise_s, np.where(self.off_a_ledge, fall_s, 0.0))

    @cached_property
    def off_a_ledge(self) -> np.ndarray:
        """(E,) True for the edges an agent takes by running off a ledge: drops, jumps down."""
        return np.isin(self.edge_kind, (EdgeKind.JUMP, EdgeKind.DROP)) & (self.edge_rise_m < 0)

    @cached_property
    def edge_climb_s(self) -> np.ndarray:
        """(E,) seconds each ladder edge takes at the climbing speed, 0 for every other edge."""
        climb = self.edge_kind == EdgeKind.LADDER
        return np.where(climb, self.edge_length / LADDER_SPEED_M_S, 0.0)

    @cached_property
    def edge_run_m(self) -> np.ndarray:
        """(E,) metres of each edge an agent runs at its own speed: its length; none off a ledge
        (crossed in its fall, `edge_air_s`) or of a ladder (climbed at the climbing speed,
        `edge_climb_s`)."""
        none = (self.edge_kind == EdgeKind.LADDER) | self.off_a_ledge
        return np.where(none, 0.0, self.edge_length)

    @cached_property
    def edge_fixed_s(self) -> np.ndarray:
        """(E,) seconds of each edge whatever the agent's speed: rising, falling, climbing. The
        replay plans an edge as these plus `edge_run_m` run at one speed."""
        return self.edge_air_s + self.edge_climb_s

    @cached_property
    def edge_cost(self) -> np.ndarray:
        """(E,) what an edge costs a route, in metres: what an agent runs of it plus the
        distance it would have run (at knife speed) while it rises, falls or climbs; a drop
        with fall damage costs its length on top, so a route takes such a fall only where it
        saves at least that much running (a player keeps his HP where a ladder or stairs are
        about as quick: a rule chosen, not measured)."""
        damage = np.where(self.fall_m > 0, self.edge_length, 0.0)
        return self.edge_run_m + RUN_SPEED_M_S * self.edge_fixed_s + damage

    @cached_property
    def adjacency(self) -> csr_matrix:
        """Sparse (N, N) matrix of edge costs (`edge_cost`), for scipy's graph routines."""
        return csr_matrix(
            (self.edge_cost, (self.edge_source, self.edge_target)),
            shape=(self.num_nodes, self.num_nodes),
        )

    @cached_property
    def out_edges(self) -> np.ndarray:
        """(N, 8) edge index leaving each node in each compass direction, -1 where none."""
        table = np.full((self.num_nodes, 8), -1, dtype=np.int64)
        table[self.edge_source, self.edge_direction] = np.arange(self.num_edges)
        return table

    @cached_property
    def allowed_actions(self) -> tuple[np.ndarray, np.ndarray]:
        """Every node's possible actions (`action_mask`) in one list: (first, actions), the
        actions of node i ascending in actions[first[i]:first[i + 1]]; first has N + 1 rows."""
        mask = np.ones((self.num_nodes, 9), dtype=bool)
        mask[:, :8] = self.out_edges >= 0
        first = np.zeros(self.num_nodes + 1, dtype=np.int64)
        np.cumsum(mask.sum(axis=1), out=first[1:])
        return first, np.nonzero(mask)[1].astype(np.int64)

    def action_mask(self, node: int) -> np.ndarray:
        """Which of the 9 actions (8 moves, STOP) are possible at a node."""
        mask = np.ones(9, dtype=np.int8)
        mask[:8] = self.out_edges[node] >= 0
        return mask

    def region_of(self, name: str) -> np.ndarray:
        """Node indices of a region (for example 'bombsite_a'); a GraphError if unknown."""
        if name not in self.regions:
            raise GraphError(f"unknown region {name!r}; known: {', '.join(sorted(self.regions))}")
        return self.regions[name]

    # ---- nearest waypoint -------------------------------------------------------------------

    @cached_property
    def ladders(self) -> np.ndarray:
        """(L,) one edge of each ladder (the one from its lower end), in edge order."""
        return np.flatnonzero((self.edge_kind == EdgeKind.LADDER) & (self.edge_rise_m > 0))

    @cached_property
    def ladder_between(self) -> dict[tuple[int, int], int]:
        """The ladder edge from one end of a ladder to the other, either way, by (source,
        target): where the cheapest edge between the two is the ladder."""
        edges = np.flatnonzero(self.edge_kind == EdgeKind.LADDER)
        ends = self.edge_source[edges], self.edge_target[edges]
        cheapest = self.edges_between(*ends)
        return {
            (int(a), int(b)): int(edge)
            for a, b, edge in zip(*ends, cheapest, strict=True)
            if self.edge_kind[edge] == EdgeKind.LADDER
        }

    def on_ladders(self, points: np.ndarray, reach: float = LADDER_REACH_M) -> np.ndarray:
        """(M, L) which of the `ladders` each of the points (M, 3) is on: between the heights of
        its two ends and within `reach` of the line between them across the floor (ladders
        that share an end overlap)."""
        points = np.asarray(points, dtype=np.float64).reshape(-1, 3)
        low, high = (
            self.positions[self.edge_source[self.ladders]],
            self.positions[self.edge_target[self.ladders]],
        )
        on = np.zeros((len(points), len(self.ladders)), dtype=bool)
        for k in range(len(self.ladders)):
            between = (points[:, 2] > low[k, 2]) & (points[:, 2] < high[k, 2])
            across = _to_segment_2d(points[:, :2], low[k, :2], high[k, :2]) <= reach
            on[:, k] = between & across
        return on

    @cached_property
    def _tree(self) -> cKDTree:
        return cKDTree(self.positions * np.array([1.0, 1.0, _Z_STRETCH]))

    def nearest(
        self, points: np.ndarray, max_distance: float = np.inf
    ) -> tuple[np.ndarray, np.ndarray]:
        """Floor-aware nearest waypoint of each point (metres, shape (M, 3) or (3,)).

        Returns (index, distance): the waypoint index (-1 where no waypoint on the query's floor
        lies within `max_distance` and the vertical band) and the true 3-D distance (inf there).
        """
        pts = np.asarray(points, dtype=np.float64)
        single = pts.ndim == 1
        pts = np.atleast_2d(pts)
        if pts.shape[1] != 3:
            raise GraphError(f"nearest() wants points of shape (M, 3), got {pts.shape}")
        if not np.all(np.isfinite(pts)):
            raise GraphError("nearest() got a NaN or infinite position")
        cand, dist = self._floor_candidates(pts, max_distance)
        ok = np.isfinite(dist)
        best = np.argmin(dist, axis=1)
        rows = np.arange(len(pts))
        index = np.where(ok[rows, best], cand[rows, best], -1)
        distance = dist[rows, best]
        if single:
            return index[:1], distance[:1]
        return index, distance

    def near(self, point: np.ndarray, max_distance: float) -> np.ndarray:
        """The waypoints on the floor of one point (metres, (3,)) within `max_distance` of it,
        nearest first, as `nearest` finds them (at most its 12 candidates)."""
        pts = np.asarray(point, dtype=np.float64).reshape(1, 3)
        if not np.all(np.isfinite(pts)):
            raise GraphError("near() got a NaN or infinite position")
        cand, dist = self._floor_candidates(pts, max_distance)
        order = np.argsort(dist[0], kind="stable")
        return cand[0, order[np.isfinite(dist[0, order])]].astype(np.int64)

    def _floor_candidates(
        self, pts: np.ndarray, max_distance: float
    ) -> tuple[np.ndarray, np.ndarray]:
        """(candidates, 3-D distances) of each point (M, 3): its `_CANDIDATES` nearest waypoints
        in the height-stretched metric, the distance inf where one is not on the point's floor
        (the vertical band) or farther than `max_distance`."""
        k = min(_CANDIDATES, self.num_nodes)
        _, cand = self._tree.query(pts * np.array([1.0, 1.0, _Z_STRETCH]), k=k)
        cand = cand.reshape(len(pts), k)
        cand_pos = self.positions[np.minimum(cand, self.num_nodes - 1)]
        dz = cand_pos[..., 2] - pts[:, None, 2]
        dist = np.linalg.norm(cand_pos - pts[:, None, :], axis=2)
        ok = (cand < self.num_nodes) & (dz <= SNAP_MAX_ABOVE_M) & (dz >= -SNAP_MAX_BELOW_M)
        ok &= dist <= max_distance
        return cand, np.where(ok, dist, np.inf)

    # ---- shortest paths ---------------------------------------------------------------------

    @cached_property
    def edge_lookup(self) -> tuple[np.ndarray, np.ndarray]:
        """(keys, edge ids): every edge's `source * num_nodes + target`, sorted, the cheapest edge
        first among duplicates, and the edge of each key; finds the edge between two nodes by
        binary search (`np.searchsorted`). Computed once per graph."""
        keys = self.edge_source.astype(np.int64) * self.num_nodes + self.edge_target
        order = np.lexsort((self.edge_cost, keys))
        sorted_keys = keys[order]
        for shared in (sorted_keys, order):  # every path cache of the graph reads them
            shared.setflags(write=False)
        return sorted_keys, order

    def edges_between(self, sources: np.ndarray, targets: np.ndarray) -> np.ndarray:
        """(K,) the edge from each source node to its target (the cheapest where several are),
        -1 where there is none (`edge_lookup`)."""
        keys, edge_ids = self.edge_lookup
        wanted = np.asarray(sources, dtype=np.int64) * self.num_nodes + np.asarray(targets)
        if not len(keys):
            return np.full(len(wanted), -1, dtype=np.int64)
        at = np.minimum(np.searchsorted(keys, wanted), len(keys) - 1)
        return np.where(keys[at] == wanted, edge_ids[at], -1).astype(np.int64)

    def path_lengths(self, source: int) -> tuple[np.ndarray, np.ndarray]:
        """Dijkstra from one node: (path cost, `edge_cost`, to every node; predecessor of every
        node)."""
        dist, pred = dijkstra(
            self.adjacency, directed=True, indices=source, return_predecessors=True
        )
        return dist, pred

    def shortest_path(self, source: int, target: int) -> list[int]:
        """Node sequence of the shortest path from `source` to `target` (both included).

        Raises GraphError when `target` cannot be reached from `source`.
        """
        if source == target:
            return [int(source)]
        straight = float(np.linalg.norm(self.positions[target] - self.positions[source]))
        # Bounded searches first (most calls join nearby waypoints along a nearly straight
        # path), then an unbounded one.
        for limit in (1.5 * straight + 2.0, 4.0 * straight + 5.0, np.inf):
            dist, pred = dijkstra(
                self.adjacency,
                directed=True,
                indices=source,
                return_predecessors=True,
                limit=limit,
            )
            if np.isfinite(dist[target]):
                path = [int(target)]
                while path[-1] != source:
                    path.append(int(pred[path[-1]]))
                return path[::-1]
        raise GraphError(f"waypoint {target} cannot be reached from waypoint {source}")

    # ---- file format ------------------------------------------------------------------------

    def save(self, path: str | Path) -> None:
        """Write the graph as a versioned `.npz`, byte-identical for identical graphs.

        Written to a temporary file beside the target, then renamed: never half-written.
        """
        arrays: dict[str, np.ndarray] = {
            "format_version": np.array(FORMAT_VERSION, dtype=np.int32),
            "positions": np.asarray(self.positions, dtype=np.float64),
            "edge_source": np.asarray(self.edge_source, dtype=np.int32),
            "edge_target": np.asarray(self.edge_target, dtype=np.int32),
            "edge_kind": np.asarray(self.edge_kind, dtype=np.uint8),
            "edge_direction": np.asarray(self.edge_direction, dtype=np.uint8),
            "node_place": np.asarray(self.node_place, dtype=np.int16),
            "place_names": np.array(json.dumps(self.place_names)),
            "regions": np.array(
                json.dumps({k: [int(i) for i in v] for k, v in sorted(self.regions.items())})
            ),
            "meta": np.array(json.dumps(self.meta, sort_keys=True)),
        }
        if self.world_triangles is not None:
            arrays["world_triangles"] = np.asarray(self.world_triangles, dtype=np.float64)
        write_npz_atomic(Path(path), arrays)

    @classmethod
    def load(cls, path: str | Path) -> WaypointGraph:
        """Read a graph file written by `save`; a GraphError for anything else."""
        path = Path(path)
        if not path.is_file():
            raise GraphError(f"waypoint graph not found: {path}")
        try:
            with np.load(path, allow_pickle=False) as data:
                version = int(data["format_version"])
                if version != FORMAT_VERSION:
                    raise GraphError(
                        f"{path}: graph format version {version}, this decoy reads "
                        f"{FORMAT_VERSION}; rebuild it with `decoy build-waypoints`"
                    )
                graph = cls(
                    positions=data["positions"].astype(np.float64),
                    edge_source=data["edge_source"].astype(np.int32),
                    edge_target=data["edge_target"].astype(np.int32),
                    edge_kind=data["edge_kind"].astype(np.uint8),
                    edge_direction=data["edge_direction"].astype(np.uint8),
                    node_place=data["node_place"].astype(np.int16),
                    place_names=list(json.loads(str(data["place_names"]))),
                    regions={
                        k: np.asarray(v, dtype=np.int64)
                        for k, v in json.loads(str(data["regions"])).items()
                    },
                    meta=json.loads(str(data["meta"])),
                    world_triangles=(
                        data["world_triangles"].astype(np.float64)
                        if "world_triangles" in data.files
                        else None
                    ),
                )
        except GraphError:
            raise
        except Exception as error:
            # A damaged file fails in many ways (zlib.error, BadZipFile, tokenize.TokenError from
            # the .npy header, NotImplementedError for an unknown zip method, TypeError or
            # AttributeError for members of the wrong shape): all of them are a bad graph file.
            raise GraphError(f"{path}: not a readable waypoint graph ({error})") from None
        graph.validate(path)
        return graph

    def validate(self, origin: str | Path = "graph") -> None:
        """Check array shapes and index ranges; a GraphError names the first problem."""
        n = len(self.positions)
        problems = []
        if self.positions.ndim != 2 or self.positions.shape[1] != 3:
            problems.append("positions are not (N, 3)")
        if not np.all(np.isfinite(self.positions)):
            problems.append("positions hold NaN")
        e = len(self.edge_source)
        if not all(len(a) == e for a in (self.edge_target, self.edge_kind, self.edge_direction)):
            problems.append("edge arrays differ in length")
        elif e and (
            min(self.edge_source.min(), self.edge_target.min()) < 0
            or max(self.edge_source.max(), self.edge_target.max()) >= n
        ):
            problems.append("an edge points outside the node list")
        if len(self.node_place) != n:
            problems.append("node_place length differs from the node count")
        world = self.world_triangles
        if world is not None and (
            world.ndim != 3 or world.shape[1:] != (3, 3) or not np.all(np.isfinite(world))
        ):
            problems.append("its world is not finite (T, 3, 3) triangles")
        if problems:
            raise GraphError(f"{origin}: corrupt waypoint graph ({problems[0]})")


def write_npz_atomic(path: Path, arrays: dict[str, np.ndarray]) -> None:
    """Write arrays as a deterministic `.npz` (fixed timestamps), atomically."""

    def write(tmp: Path) -> None:
        with zipfile.ZipFile(tmp, "w", zipfile.ZIP_DEFLATED) as zf:
            for name, array in arrays.items():
                buffer = io.BytesIO()
                np.lib.format.write_array(buffer, np.asarray(array), allow_pickle=False)
                info = zipfile.ZipInfo(f"{name}.npy", date_time=(1980, 1, 1, 0, 0, 0))
                info.compress_type = zipfile.ZIP_DEFLATED
                info.external_attr = 0o644 << 16
                zf.writestr(info, buffer.getvalue())

    write_atomic(path, write)
