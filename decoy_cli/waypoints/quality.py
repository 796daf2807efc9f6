"""How well a waypoint graph covers real player positions (snap quality, alignment check).

Two distances are reported for every position: the 3-D distance to its floor-aware nearest
waypoint, and the horizontal one. They differ for airborne players: about one real T position in
ten is 0.4-1.1 m above the floor (jumps), so the 3-D figure mixes the data's jumps into the
graph's coverage, while the horizontal one measures coverage alone. Given the world's floor
height under each position, the 3-D share is also reported for the positions on the ground
(at most `AIRBORNE_M` above the floor), which is the graph's coverage of where players stand.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from decoy_cli.errors import DecoyError
from decoy_cli.waypoints.graph import WaypointGraph, in_the_air
from decoy_cli.world.world import World

ALIGNED_WITHIN_M = 0.5


@dataclass(frozen=True)
class SnapQuality:
    """Snap distances of a set of positions to a graph (metres; shares in [0, 1])."""

    positions: int
    unsnapped: int  # no waypoint on the position's floor within the search radius
    median_3d: float
    p95_3d: float
    within_3d: float
    median_horizontal: float
    p95_horizontal: float
    within_horizontal: float
    on_pruned: float | None  # share whose nearest lattice node was pruned (None: not known)
    airborne: int | None = None  # positions in the air (`in_the_air`; None: unknown)
    grounded_within_3d: float | None = None  # within_3d over the positions on the ground

    def as_dict(self) -> dict[str, float | int | None]:
        return dict(self.__dict__)


def snap_quality(
    graph: WaypointGraph,
    positions: np.ndarray,
    pruned_positions: np.ndarray | None = None,
    max_distance: float = 3.0,
    floor_z: np.ndarray | None = None,
    vertical_speed: np.ndarray | None = None,
) -> SnapQuality:
    """Snap every position (metres, (M, 3)) and summarise the distances; `floor_z` (M,), the
    world's floor height under each position (NaN: unknown), separates the airborne ones, as
    does a known non-zero `vertical_speed` (M,) (awpy's velocityZ, m/s), as in the replay."""
    positions = np.asarray(positions, dtype=np.float64).reshape(-1, 3)
    index, dist = graph.nearest(positions, max_distance=max_distance)
    ok = index >= 0
    horizontal = np.full(len(positions), np.inf)
    horizontal[ok] = np.linalg.norm(positions[ok, :2] - graph.positions[index[ok], :2], axis=1)
    on_pruned = None
    if pruned_positions is not None:
        on_pruned = 0.0
        if len(pruned_positions):
            both = WaypointGraph(
                positions=np.vstack([graph.positions, pruned_positions]),
                edge_source=np.zeros(0, np.int32),
                edge_target=np.zeros(0, np.int32),
                edge_kind=np.zeros(0, np.uint8),
                edge_direction=np.zeros(0, np.uint8),
                node_place=np.full(graph.num_nodes + len(pruned_positions), -1, np.int16),
                place_names=[],
                regions={},
            )
            nearest_any, _ = both.nearest(positions, max_distance=max_distance)
            on_pruned = float(np.mean(nearest_any >= graph.num_nodes))

    def pct(values: np.ndarray, q: float) -> float:
        """Percentile; inf where it falls among unsnapped positions (inf - inf is not a NaN
        warning on the user's terminal), NaN for no values."""
        if not len(values):
            return float("nan")
        with np.errstate(invalid="ignore"):
            result = float(np.percentile(values, q))
        return np.inf if np.isnan(result) else result

    return SnapQuality(
        positions=len(positions),
        unsnapped=int(np.sum(~ok)),
        median_3d=pct(dist[ok], 50),
        p95_3d=pct(dist, 95) if ok.all() else pct(np.where(ok, dist, np.inf), 95),
        within_3d=float(np.mean(dist <= ALIGNED_WITHIN_M)) if len(dist) else float("nan"),
        median_horizontal=pct(horizontal[ok], 50),
        p95_horizontal=pct(horizontal, 95),
        within_horizontal=float(np.mean(horizontal <= ALIGNED_WITHIN_M))
        if len(horizontal)
        else float("nan"),
        on_pruned=on_pruned,
        **_grounded(positions, dist, floor_z, vertical_speed),
    )


def _grounded(
    positions: np.ndarray,
    dist: np.ndarray,
    floor_z: np.ndarray | None,
    vertical_speed: np.ndarray | None,
) -> dict:
    """The airborne count and the 3-D share within reach on the ground (none without floors)."""
    if floor_z is None:
        return {}
    airborne = in_the_air(positions[:, 2], np.asarray(floor_z, dtype=np.float64), vertical_speed)
    ground = dist[~airborne]
    share = float(np.mean(ground <= ALIGNED_WITHIN_M)) if len(ground) else float("nan")
    return {"airborne": int(airborne.sum()), "grounded_within_3d": share}


def esta_positions(path: str | Path) -> tuple[np.ndarray, np.ndarray]:
    """Every alive player position (metres) in the rounds of a match file or folder, and its
    vertical speed (awpy's velocityZ, m/s; NaN where the file has none)."""
    from decoy_cli.esta.reader import iter_match_files, read_match

    chunks, speeds = [], []
    for file in iter_match_files(path):
        for round_ in read_match(file).rounds:
            chunks.append(round_.position[round_.alive])
            speeds.append(round_.vertical_speed[round_.alive])
    if not chunks:
        return np.zeros((0, 3)), np.zeros(0)
    return np.concatenate(chunks), np.concatenate(speeds)


def alignment_quality(
    graph: WaypointGraph, pruned_positions: np.ndarray, world: World, path: str | Path
) -> SnapQuality:
    """Snap quality of the alive positions of the ESTA file or folder `path` on a graph built
    on `world`, with the world's floor under each position (for the on-the-ground share)."""
    from decoy_cli.world.physics import PhysicsWorld

    positions, vertical_speed = esta_positions(path)
    floor_z = None
    if len(positions):
        with PhysicsWorld(world) as physics:
            floor_z = physics.floor_under_feet(positions)
    return snap_quality(
        graph, positions, pruned_positions, floor_z=floor_z, vertical_speed=vertical_speed
    )


def check_aligned(quality: SnapQuality, min_aligned: float) -> None:
    """A DecoyError when fewer than `min_aligned` of the positions lie within 0.5 m of a
    waypoint horizontally: the mesh is most likely misaligned."""
    if quality.within_horizontal < min_aligned:
        raise DecoyError(
            f"only {quality.within_horizontal:.1%} of the positions lie within "
            f"{ALIGNED_WITHIN_M:g} m of a waypoint: the mesh looks misaligned (check --units, "
            "--scale, --up-axis, --offset)"
        )
