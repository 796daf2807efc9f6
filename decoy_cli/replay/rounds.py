"""Snap and plan a whole round: every player's snap result and timed plan, plus a summary table.

`snap_round` takes anything with the attributes of the ESTA reader's `Round` (duck-typed, so this
module does not import the reader): `position` (P, F, 3) metres, NaN where absent; `alive` (P, F)
bool; `weapon` (P, F) weapon names; `frame_seconds` (F,); `players`, each with `name` and `side`.
Given the physics world, frames in the air are found by a ray down from each position and left
unsnapped (see `decoy_cli.replay.snapping`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pandas as pd

from decoy_cli.errors import EstaError
from decoy_cli.esta import PlayerInfo, Round
from decoy_cli.replay.plans import PathCache, PlayerPlan, build_plan
from decoy_cli.replay.snapping import (
    DEFAULT_MAX_SNAP_M,
    WITHIN_M,
    SnapResult,
    SnapStatus,
    snap_into_sites,
    snap_positions,
)
from decoy_cli.waypoints.graph import WaypointGraph
from decoy_cli.world.physics import PhysicsWorld

SUMMARY_COLUMNS = (
    "player",
    "side",
    "frames_alive",
    "snap_median_m",
    "snap_p95_m",
    "snap_max_m",
    f"within_{WITHIN_M:g}m",
    "unsnappable",
    "airborne",
    "intervals",
    "infeasible",
    "worst_ratio",
    "unreachable",
    "path_length_m",
    "died_s",
)
"""Columns of `RoundPlan.summary`, one row per player."""


@dataclass(frozen=True)
class RoundPlan:
    """Snap results and timed plans of every player of one round, in the round's player order."""

    players: list[PlayerInfo]
    """The round's players, in its row order."""
    frame_seconds: np.ndarray
    """(F,) frame times, seconds since freeze-time end."""
    snaps: list[SnapResult]
    plans: list[PlayerPlan]
    summary: pd.DataFrame
    """One row per player with `SUMMARY_COLUMNS`: snap quality, plan feasibility, fate.

    `within_0.5m` is the share of alive frames with a position that snapped within 0.5 m;
    `unsnappable` counts alive frames with no waypoint on their floor, `airborne` those in the
    air (found only with the world, not snapped and not in `within_0.5m`); `worst_ratio` is the
    largest required / maximum speed ratio; `died_s` is NaN for a survivor.
    """

    @property
    def num_infeasible(self) -> int:
        return sum(plan.num_infeasible for plan in self.plans)

    @property
    def num_unreachable(self) -> int:
        return sum(plan.num_unreachable for plan in self.plans)

    @property
    def num_unsnappable(self) -> int:
        return sum(snap.num_unsnappable for snap in self.snaps)


def snap_round(
    round_: Round,
    graph: WaypointGraph,
    *,
    max_distance: float = DEFAULT_MAX_SNAP_M,
    physics: PhysicsWorld | None = None,
    sites: np.ndarray | None = None,
    node_site: np.ndarray | None = None,
) -> RoundPlan:
    """Snap every player of a round to the graph and build its timed plan (one shared path cache).

    With `physics` (the world the graph was built on), frames in the air are not snapped. With
    `sites` (P, F), the bomb site each player must stand in at each frame ("" where free), and
    `node_site`, the site of every waypoint, those frames snap inside their site
    (`snap_into_sites`).

    Inconsistent round arrays raise EstaError; an unknown weapon name raises EstaError.
    """
    positions = np.asarray(round_.position, dtype=np.float64)
    alive = np.asarray(round_.alive, dtype=bool)
    weapons = np.asarray(round_.weapon)
    seconds = np.asarray(round_.frame_seconds, dtype=np.float64)
    players = list(round_.players)
    shape = (len(players), len(seconds))
    if positions.shape != (*shape, 3):
        raise EstaError(f"round positions have shape {positions.shape}, expected {(*shape, 3)}")
    for name, array in (("alive flags", alive), ("weapons", weapons)):
        if array.shape != shape:
            raise EstaError(f"round {name} have shape {array.shape}, expected {shape}")

    floor_z = np.full(shape, np.nan) if physics is None else physics.floor_under_feet(positions)
    paths = PathCache(graph)
    snaps: list[SnapResult] = []
    plans: list[PlayerPlan] = []
    for p in range(len(players)):
        snap = snap_positions(
            graph,
            positions[p],
            alive[p],
            max_distance=max_distance,
            floor_z=floor_z[p],
            vertical_speed=None if physics is None else round_.vertical_speed[p],
        )
        if sites is not None and node_site is not None and (sites[p] != "").any():
            snap = snap_into_sites(graph, snap, positions[p], sites[p], node_site, max_distance)
        present = np.isfinite(positions[p]).all(axis=1)
        plan = build_plan(
            graph, snap.node, seconds, alive[p], weapons[p], present=present, paths=paths
        )
        snaps.append(snap)
        plans.append(plan)
    rows = [_summary_row(player, alive[p], snaps[p], plans[p]) for p, player in enumerate(players)]
    summary = pd.DataFrame(rows, columns=list(SUMMARY_COLUMNS))
    return RoundPlan(
        players=players, frame_seconds=seconds, snaps=snaps, plans=plans, summary=summary
    )


def _summary_row(player: PlayerInfo, alive: np.ndarray, snap: SnapResult, plan: PlayerPlan) -> list:
    """One summary row, in `SUMMARY_COLUMNS` order."""
    errors = snap.error_m[snap.status == SnapStatus.SNAPPED]
    with_position = snap.num_snapped + snap.num_unsnappable
    if len(errors):
        median, p95, worst = np.percentile(errors, [50, 95, 100])
    else:
        median = p95 = worst = np.nan
    within = np.count_nonzero(errors <= WITHIN_M) / with_position if with_position else np.nan
    return [
        str(player.name),
        str(player.side),
        int(np.count_nonzero(alive)),
        float(median),
        float(p95),
        float(worst),
        float(within),
        snap.num_unsnappable,
        snap.num_airborne,
        plan.num_intervals,
        plan.num_infeasible,
        plan.worst_ratio,
        plan.num_unreachable,
        plan.total_length_m,
        plan.death_seconds,
    ]
