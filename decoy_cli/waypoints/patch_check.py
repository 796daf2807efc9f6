"""Which learned floor patches a waypoint graph is better with: real paths against real positions.

Why: a learned patch (`decoy_cli/world/patch_learning.py`) is a solid box where players stood
again and again. It gives the graph waypoints on its top, where those players were; but a solid
box also takes floor and headroom from the ways players walk beside or under it (a slab learned
over half of a walkway, a box that fills a doorway because players stood on its edge), and a
replay sent round it arrives late. Counting both on the learning matches decides which patches
stay.

Method, on the graph built without any learned patch (bare) and with every candidate (patched):

1. **What a patch costs.** Each pair of consecutive frames of a real player at two different
   bare waypoints (each within `ALIGNED_WITHIN_M`; the path on one of the graphs at most
   `BARE_LIMIT_M`) is compared with the patched graph. The pair is *lengthened* when the
   patched path costs (`edge_cost`) more than `LENGTHENED_RATIO` times the bare one plus
   `LENGTHENED_EXTRA_M`, or when an end has no patched waypoint within `ALIGNED_WITHIN_M`
   because a box fills the spot the player stood in (deeper inside it than the learning grows
   a box; an end at a box's edge leaves the pair out). Each lengthened pair is blamed on the
   patches whose box holds a waypoint of the bare path, the box grown by one lattice spacing
   sideways, `BLAME_BELOW_M` down and a step up: the box took that way.
2. **What a patch gives.** Real positions within `ALIGNED_WITHIN_M` of a patched waypoint on the
   patch's top (within a step of it) that have no bare waypoint that near; and pairs the
   patched graph joins by a much shorter path (the same rule the other way: a way up the
   patch opens), credited to the patches beside the patched path in the same way.
3. **Verdict.** A patch is left out when the pairs blamed on it come from at least
   `MIN_LENGTHENED_MATCHES` matches and outnumber what it gives.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from scipy.sparse.csgraph import dijkstra

from decoy_cli.csgo import HAMMER_TO_M, JUMP_HEIGHT_M, PLAYER_HEIGHT_M, STEP_HEIGHT_M
from decoy_cli.waypoints.build import build_graph
from decoy_cli.waypoints.graph import WaypointGraph
from decoy_cli.waypoints.lattice import LatticeResult
from decoy_cli.waypoints.lattice_params import LatticeParams
from decoy_cli.waypoints.quality import ALIGNED_WITHIN_M
from decoy_cli.world import patch_learning
from decoy_cli.world.nav_data import PATCH_COLUMNS
from decoy_cli.world.navmesh import load_navmesh, nav_world
from decoy_cli.world.patch_boxes import CELL_U
from decoy_cli.world.patch_learning import MIN_MATCHES, PatchBox, Tracks
from decoy_cli.world.physics import PhysicsWorld

LENGTHENED_RATIO = 1.5
"""A patched path longer than this many times the bare one is a detour, not a difference of
the lattice's zig-zag between two builds."""

LENGTHENED_EXTRA_M = 3.0
"""...plus this much: more than a data frame's run at the fastest speed (250 u/s for 0.5 s,
2.4 m), so a lengthened pair makes a replay at least a frame late."""

BARE_LIMIT_M = 20.0
"""Longest path between consecutive frames, on either graph, for the pair to be compared;
longer ones on both (a teleport, a position glitch) say nothing about a patch."""

BLAME_BELOW_M = PLAYER_HEIGHT_M + JUMP_HEIGHT_M
"""How far below a box its bare-path waypoints are blamed: a standing player's height plus a
crouch-jump's rise (game rules) is the most headroom a box can take from a path under it.
Above, a step: a box takes nothing from a path over its top."""

MIN_LENGTHENED_MATCHES = 2
"""Fewest matches the paths blamed on a patch must come from to leave it out: one match's
detour can be one player's habit."""

TOP, BOTTOM = PATCH_COLUMNS.index("z_top"), PATCH_COLUMNS.index("z_bottom")
"""Columns of a box row (`PatchBox.box`, the patches file's order)."""

_SOURCES_PER_SEARCH = 256
"""Dijkstra sources searched together (each a row of the graph's size)."""


@dataclass(frozen=True)
class PatchVerdict:
    """What one learned patch costs and gives on the learning matches, and whether it stays."""

    patch: int
    lengthened: int
    """Lengthened consecutive-frame pairs of real players blamed on the patch (a pair next to
    several patches is blamed on each)."""
    lengthened_matches: int
    """Matches those pairs come from."""
    gained: int
    """Real positions on the patch's top that only the patched graph has a waypoint near."""
    shortened: int = 0
    """Consecutive-frame pairs of real players the patched graph joins by a much shorter path
    (the same rule as lengthened, the other way) that runs beside the patch."""

    @property
    def kept(self) -> bool:
        return not (
            self.lengthened_matches >= MIN_LENGTHENED_MATCHES
            and self.lengthened > self.gained + self.shortened
        )


@dataclass(frozen=True)
class PatchCheck:
    """The verdict on every patch, and the pairs compared."""

    verdicts: tuple[PatchVerdict, ...]
    pairs: int
    lengthened_pairs: int

    def kept_boxes(self, boxes: Sequence[PatchBox]) -> list[PatchBox]:
        """The boxes of the patches that stay, each with its verdict's counts as evidence."""
        verdict = {v.patch: v for v in self.verdicts}
        return [
            b.with_check(
                verdict[b.patch].lengthened, verdict[b.patch].gained, verdict[b.patch].shortened
            )
            for b in boxes
            if verdict[b.patch].kept
        ]


@dataclass(frozen=True)
class LearnedPatches:
    """The patches learned from a set of matches, the check that weighed them, those kept."""

    candidates: tuple[PatchBox, ...]
    check: PatchCheck | None
    """None when nothing was learned."""
    kept: tuple[PatchBox, ...]
    standing_positions: int
    built: tuple[WaypointGraph, LatticeResult] | None
    """The graph on the kept patches when the check already built it (all or none kept)."""


def learn_checked_patches(
    files: Sequence[Path],
    map_id: str,
    seeds: np.ndarray | None = None,
    params: LatticeParams = LatticeParams(),
    manual: np.ndarray | None = None,
    min_matches: int = MIN_MATCHES,
) -> LearnedPatches:
    """Learn patches from `files` on the map's bare nav world, build the graph without and with
    them (as the final graph will be built: same seeds, lattice and manual points) and keep the
    patches the learning matches' paths are better with."""
    nav = load_navmesh(map_id)
    standing, tracks = patch_learning.read_positions(files, map_id, nav)
    bare_world = nav_world(map_id, ())
    with PhysicsWorld(bare_world) as physics:
        candidates = patch_learning.learn_patches(standing, physics, nav, min_matches=min_matches)
    if not candidates:
        return LearnedPatches((), None, (), len(standing.position), None)
    bare = build_graph(bare_world, map_id, seeds, params, manual)
    patched_world = nav_world(map_id, tuple(b.box for b in candidates))
    patched = build_graph(patched_world, map_id, seeds, params, manual)
    check = check_patches(bare[0], patched[0], candidates, tracks, params)
    kept = tuple(check.kept_boxes(candidates))
    built = patched if len(kept) == len(candidates) else bare if not kept else None
    return LearnedPatches(
        candidates=tuple(candidates),
        check=check,
        kept=kept,
        standing_positions=len(standing.position),
        built=built,
    )


def check_patches(
    bare: WaypointGraph,
    patched: WaypointGraph,
    boxes: Sequence[PatchBox],
    tracks: Tracks,
    params: LatticeParams = LatticeParams(),
) -> PatchCheck:
    """Weigh every learned patch of `boxes` (built into `patched`, absent from `bare`) on the
    real players' `tracks` (see the module docstring)."""
    box_m = np.array([b.box for b in boxes]).reshape(-1, 6) * HAMMER_TO_M  # as the world has them
    patch_of_box = np.array([b.patch for b in boxes], dtype=np.int64)
    patches = sorted(set(patch_of_box.tolist()))
    on_bare, on_patched = _snapped(bare, tracks), _snapped(patched, tracks)
    blamed, credited, pairs, lengthened = _path_changes(
        bare, patched, (on_bare, on_patched), box_m, patch_of_box, tracks, params
    )
    gained = _gained(patched, (on_bare, on_patched), box_m, patch_of_box)
    verdicts = tuple(
        PatchVerdict(
            patch=p,
            lengthened=len(blamed.get(p, ())),
            lengthened_matches=len(set(blamed.get(p, ()))),
            gained=int(gained.get(p, 0)),
            shortened=int(credited.get(p, 0)),
        )
        for p in patches
    )
    return PatchCheck(verdicts=verdicts, pairs=pairs, lengthened_pairs=lengthened)


def _snapped(graph: WaypointGraph, tracks: Tracks) -> np.ndarray:
    """The waypoint within `ALIGNED_WITHIN_M` of every track position (-1: none)."""
    if len(tracks.position) == 0:
        return np.zeros(0, dtype=np.int64)
    index, _ = graph.nearest(tracks.position, max_distance=ALIGNED_WITHIN_M)
    return index


def _path_changes(
    bare: WaypointGraph,
    patched: WaypointGraph,
    snapped: tuple[np.ndarray, np.ndarray],
    box_m: np.ndarray,
    patch_of_box: np.ndarray,
    tracks: Tracks,
    params: LatticeParams,
) -> tuple[dict[int, list[int]], dict[int, int], int, int]:
    """({patch: match of each lengthened pair blamed on it}, {patch: shortened pairs credited
    to it}, pairs compared, pairs lengthened)."""
    on_bare, on_patched = snapped
    end = np.flatnonzero(tracks.follows)
    start = end - 1
    a0, b0, a1, b1 = on_bare[start], on_bare[end], on_patched[start], on_patched[end]
    use = (a0 >= 0) & (b0 >= 0) & (a0 != b0)
    a0, b0, a1, b1, end = a0[use], b0[use], a1[use], b1[use], end[use]
    limit = LENGTHENED_RATIO * BARE_LIMIT_M + LENGTHENED_EXTRA_M
    bare_cost = _path_costs(bare, a0, b0, limit)
    on_both = (a1 >= 0) & (b1 >= 0)
    patched_cost = np.full(len(a1), np.inf)
    patched_cost[on_both] = _path_costs(patched, a1[on_both], b1[on_both], limit)
    # an end with no patched waypoint is lengthened when a box fills the spot (it stands deep
    # inside one), else not compared (the box's edge grew over the player's feet)
    position = tracks.position
    filled = (a1 >= 0) | _deep_inside(position[end - 1], box_m, patch_of_box)
    filled &= (b1 >= 0) | _deep_inside(position[end], box_m, patch_of_box)
    compared = ((bare_cost <= BARE_LIMIT_M) | (patched_cost <= BARE_LIMIT_M)) & filled
    with np.errstate(invalid="ignore"):
        worse = compared & (patched_cost > LENGTHENED_RATIO * bare_cost + LENGTHENED_EXTRA_M)
        better = compared & (bare_cost > LENGTHENED_RATIO * patched_cost + LENGTHENED_EXTRA_M)
    blamed: dict[int, list[int]] = {}
    for row in np.flatnonzero(worse).tolist():
        for patch in _patches_beside(bare, int(a0[row]), int(b0[row]), box_m, patch_of_box, params):
            blamed.setdefault(patch, []).append(int(tracks.match[end[row]]))
    credited: dict[int, int] = {}
    for row in np.flatnonzero(better).tolist():
        near = _patches_beside(patched, int(a1[row]), int(b1[row]), box_m, patch_of_box, params)
        for patch in near:
            credited[patch] = credited.get(patch, 0) + 1
    return blamed, credited, int(compared.sum()), int(worse.sum())


def _deep_inside(position: np.ndarray, box_m: np.ndarray, patch_of_box: np.ndarray) -> np.ndarray:
    """(N,) whether each position stands in a patch's boxes (between a box's bottom and a step
    above its top) more than one learned column (`CELL_U`) from the patch's edge: where the
    box fills a spot, not where its edge was grown over a player's feet."""
    reach = CELL_U * HAMMER_TO_M
    probes = np.array([[0.0, 0.0], [reach, 0.0], [-reach, 0.0], [0.0, reach], [0.0, -reach]])
    deep = np.zeros(len(position), dtype=bool)
    for patch in np.unique(patch_of_box).tolist():
        mine = box_m[patch_of_box == patch]
        height = (position[:, None, 2] >= mine[:, BOTTOM]) & (
            position[:, None, 2] <= mine[:, TOP] + STEP_HEIGHT_M
        )
        everywhere = np.ones(len(position), dtype=bool)
        for dx, dy in probes:
            x, y = position[:, None, 0] + dx, position[:, None, 1] + dy
            inside = (x >= mine[:, 0]) & (x <= mine[:, 2]) & (y >= mine[:, 1]) & (y <= mine[:, 3])
            everywhere &= (inside & height).any(axis=1)
        deep |= everywhere
    return deep


def _patches_beside(
    graph: WaypointGraph,
    source: int,
    target: int,
    box_m: np.ndarray,
    patch_of_box: np.ndarray,
    params: LatticeParams,
) -> set[int]:
    """The patches whose box holds a waypoint of the graph's shortest path from `source` to
    `target`: grown by one lattice spacing sideways, `BLAME_BELOW_M` down and a step up."""
    nodes = graph.positions[graph.shortest_path(source, target)]
    grow = params.spacing
    hit = (
        (nodes[:, None, 0] >= box_m[:, 0] - grow)
        & (nodes[:, None, 1] >= box_m[:, 1] - grow)
        & (nodes[:, None, 0] <= box_m[:, 2] + grow)
        & (nodes[:, None, 1] <= box_m[:, 3] + grow)
        & (nodes[:, None, 2] >= box_m[:, BOTTOM] - BLAME_BELOW_M)
        & (nodes[:, None, 2] <= box_m[:, TOP] + STEP_HEIGHT_M)
    ).any(axis=0)
    return set(patch_of_box[hit].tolist())


def _path_costs(
    graph: WaypointGraph, source: np.ndarray, target: np.ndarray, limit: float
) -> np.ndarray:
    """Shortest-path cost from each source to its target; inf beyond `limit` metres."""
    cost = np.full(len(source), np.inf)
    unique, inverse = np.unique(source, return_inverse=True)
    for first in range(0, len(unique), _SOURCES_PER_SEARCH):
        rows = unique[first : first + _SOURCES_PER_SEARCH]
        dist = dijkstra(graph.adjacency, directed=True, indices=rows, limit=limit)
        mine = np.flatnonzero((inverse >= first) & (inverse < first + len(rows)))
        cost[mine] = dist[inverse[mine] - first, target[mine]]
    return cost


def _gained(
    patched: WaypointGraph,
    snapped: tuple[np.ndarray, np.ndarray],
    box_m: np.ndarray,
    patch_of_box: np.ndarray,
) -> dict[int, int]:
    """{patch: real positions near a patched waypoint on its top and far from every bare one}."""
    on_bare, on_patched = snapped
    node = patched.positions
    node_patch = np.full(patched.num_nodes, -1, dtype=np.int64)
    for box, patch in zip(box_m, patch_of_box, strict=True):
        on_top = (
            (node[:, 0] >= box[0])
            & (node[:, 0] <= box[2])
            & (node[:, 1] >= box[1])
            & (node[:, 1] <= box[3])
            & (np.abs(node[:, 2] - box[TOP]) <= STEP_HEIGHT_M)
        )
        node_patch[on_top] = patch
    owner = node_patch[on_patched[(on_patched >= 0) & (on_bare < 0)]]
    patches, counts = np.unique(owner[owner >= 0], return_counts=True)
    return dict(zip(patches.tolist(), counts.tolist(), strict=True))
