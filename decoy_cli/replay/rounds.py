"""Snap and plan a whole round: every player's snap result and timed plan, plus a summary table.

`snap_round` takes anything with the attributes of the ESTA reader's `Round` (duck-typed, so this
module does not import the reader): `position` (P, F, 3) metres, NaN where absent; `alive` (P, F)
bool; `weapon` (P, F) weapon names; `frame_seconds` (F,); `players`, each with `name` and `side`.
Given the physics world, frames in the air are found by a ray down from each position and left
unsnapped (see `decoy_cli.replay.snapping`); the waypoint on the floor under such a frame is a
soft target of the plan (`plan_player`). So are snapped frames denser than the lattice resolves
(`hard_frames`): whatever the data's frame rate, the plan keeps time with the same motion.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pandas as pd

from decoy_cli.csgo import TICK_RATE
from decoy_cli.errors import EstaError
from decoy_cli.esta import PlayerInfo, Round
from decoy_cli.replay.pace import MAX_ZIGZAG, less_climbed
from decoy_cli.replay.plans import PathCache, PlayerPlan, build_plan
from decoy_cli.replay.snapping import (
    DEFAULT_MAX_SNAP_M,
    WITHIN_M,
    SnapResult,
    SnapStatus,
    snap_into_sites,
    snap_positions,
)
from decoy_cli.replay.targets import hard_frames, lacks_the_way, resnap, target_seconds
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
    caps: list[np.ndarray]
    """Per plan, (T-1,) how fast the replayed agent may run over each interval, m/s
    (`interval_caps`)."""
    summary: pd.DataFrame
    """One row per player with `SUMMARY_COLUMNS`: snap quality, plan feasibility, fate.

    `within_0.5m` is the share of alive frames with a position that snapped within 0.5 m;
    `unsnappable` counts alive frames with no waypoint on their floor, `airborne` those in the
    air or on a ladder (found only with the world, not snapped and not in `within_0.5m`);
    `worst_ratio` is the largest required / maximum speed ratio; `died_s` is NaN for a survivor.
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
    caps: list[np.ndarray] = []
    for p in range(len(players)):
        snap = snap_positions(
            graph,
            positions[p],
            alive[p],
            max_distance=max_distance,
            floor_z=floor_z[p],
            vertical_speed=None if physics is None else round_.vertical_speed[p],
            seconds=seconds,
        )
        if sites is not None and node_site is not None and (sites[p] != "").any():
            snap = snap_into_sites(graph, snap, positions[p], sites[p], node_site, max_distance)
        plan, cap = plan_player(graph, snap, positions[p], seconds, alive[p], weapons[p], paths)
        snaps.append(snap)
        plans.append(plan)
        caps.append(cap)
    rows = [_summary_row(player, alive[p], snaps[p], plans[p]) for p, player in enumerate(players)]
    summary = pd.DataFrame(rows, columns=list(SUMMARY_COLUMNS))
    return RoundPlan(
        players=players,
        frame_seconds=seconds,
        snaps=snaps,
        plans=plans,
        caps=caps,
        summary=summary,
    )


def plan_player(
    graph: WaypointGraph,
    snap: SnapResult,
    positions: np.ndarray,
    seconds: np.ndarray,
    alive: np.ndarray,
    weapons: np.ndarray,
    paths: PathCache,
) -> tuple[PlayerPlan, np.ndarray]:
    """One player's timed plan (`build_plan`) through its snapped frames and, as soft targets,
    the waypoints under its frames in the air (`SnapResult.ground_node`), with its speed caps
    (`interval_caps`; `positions` (F, 3) are the player's real ones, NaN where absent).

    A player in the air is over some spot of the floor, and heading for it keeps the replay
    near the real path through a jump; its deadline is when he is there (the frame's time plus
    `SnapResult.ground_delay_s`), and one outside the times of the frames before and after is
    left out (they say where he is then). The spot under a jump across a gap or off a ledge
    may lie a long way round. Likewise a snapped frame closer in time to the last hard target
    than the lattice resolves (`hard_frames`) is a soft target: its waypoint says where the
    player went, but a waypoint a spacing off (snapping flips between neighbours, levels or
    the two sides of a door) over a fraction of a second asks more than the player ran. So a
    soft target next to an interval that makes the replay later (its expected lateness,
    `expected_lateness`, grows over the interval by more than a tick) or that it cannot reach
    is dropped and the plan rebuilt, until none is: each pass drops at least one target, so it
    ends. A soft target inside a stretch the replay runs late for another reason, on the way,
    stays. Then a hard target beside such an interval moves to a neighbouring waypoint by the
    player from which the replay keeps time (`resnap`, tried once for each pair of targets
    around it); and last an interval whose path the player cannot have taken
    (`lacks_the_way`) is crossed as a gap (`build_plan`'s `bridged`).
    """
    present = np.isfinite(positions).all(axis=1)
    snapped = (snap.node >= 0) & alive
    ground = (snap.ground_node >= 0) & (snap.node < 0)
    climbing = ground & (snap.status == SnapStatus.ON_LADDER)
    before, after = np.append(-np.inf, seconds[:-1]), np.append(seconds[1:], np.inf)
    at = np.where(ground, seconds + snap.ground_delay_s, seconds)  # when he is at the target
    ground &= climbing | ((at >= before) & (at <= after))
    at = np.maximum.accumulate(np.where(ground, np.clip(at, before, after), seconds))
    soft = (ground & ~climbing) | (snapped & ~hard_frames(seconds, snapped, target_seconds(graph)))
    nodes = np.where(snap.node >= 0, snap.node, np.where(ground, snap.ground_node, -1))
    tried: set[tuple[int, int, int]] = set()  # (frame, target before, after) `resnap` tried
    bridged = np.zeros(len(seconds), dtype=bool)
    while True:
        plan = build_plan(
            graph, nodes, at, alive, weapons, present=present, paths=paths,
            bridged=bridged, positions=positions,
        )  # fmt: skip
        caps = interval_caps(plan, positions)
        late = expected_lateness(plan, caps)
        worse = (np.diff(late) > 1.0 / TICK_RATE) | plan.interval_unreachable
        beside = np.zeros(len(plan.target_frame), dtype=bool)
        beside[:-1] |= worse
        beside[1:] |= worse
        drop = plan.target_frame[beside & soft[plan.target_frame]]
        if len(drop):
            nodes[drop] = -1
            soft[drop] = False
            continue
        retry = [t for t in np.flatnonzero(beside & snapped[plan.target_frame]).tolist() if t]
        contexts = {t: _context(plan, t) for t in retry}
        retry = [t for t in retry if contexts[t] not in tried]
        if retry:
            resnap(graph, plan, caps, np.array(retry), nodes, positions, snap.error_m, paths)
            tried.update(contexts[t] for t in retry)
            continue
        lacking = plan.target_frame[1:][lacks_the_way(plan, caps, positions)]
        if not len(lacking):
            return plan, caps
        bridged[lacking] = True


def _context(plan: PlayerPlan, t: int) -> tuple[int, int, int]:
    """(frame, waypoint of the target before, of the one after or -1) of target `t` > 0."""
    after = int(plan.target_node[t + 1]) if t + 1 < len(plan.target_node) else -1
    return int(plan.target_frame[t]), int(plan.target_node[t - 1]), after


def expected_lateness(plan: PlayerPlan, caps: np.ndarray) -> np.ndarray:
    """(T,) seconds after its deadline at which the replay reaches each target, if the agent
    leaves each target when it reaches it (or at its deadline, when early it waits) and runs
    each interval's path at most at its cap, its rises and falls taking their air time; as the
    replay's policy plays a plan. Across a gap (unreachable) the agent is placed on the target
    at its deadline, or at once when it is already late."""
    late = np.zeros(len(plan.target_node))
    deadline = plan.target_seconds
    length = np.nan_to_num(plan.interval_run_m, nan=0.0)
    with np.errstate(divide="ignore"):
        run = np.where(length > 0, length / caps, 0.0) + plan.interval_air_s
    for k in range(len(length)):
        left = deadline[k] + late[k]
        took = 0.0 if plan.interval_unreachable[k] else run[k]
        late[k + 1] = max(0.0, left + took - deadline[k + 1])
    return late


def interval_caps(plan: PlayerPlan, original: np.ndarray) -> np.ndarray:
    """Speed cap (m/s) of every interval of a plan: how fast the replayed agent may run.

    The weapon's CS:GO maximum is the speed of running on flat ground; real players beat it
    (strafe-jumps, falls: one interval in twenty in the real T rounds), and a path on the
    8-direction lattice is longer than the straight line the player ran (zig-zag, snapping). So
    the cap is the larger of the weapon's maximum and the player's own measured speed over the
    interval's running time (as the required speed: without the path's air time), times the
    path's zig-zag factor: path length over the player's own displacement (both less the
    ladders climbed, whose time is the climb's), at most `MAX_ZIGZAG`. (Measured against the
    straight line between the two snapped waypoints instead, snap jitter made agents late, and
    the real rounds' replay error grew.)
    A replay is never asked to run faster than the player did except for the lattice's
    geometry; what remains infeasible (a detour around a missing edge) stays late, and the
    lateness says so.
    """
    if len(plan.target_node) < 2:
        return np.zeros(0)
    displacement = np.linalg.norm(np.diff(original[plan.target_frame], axis=0), axis=1)
    displacement = np.nan_to_num(displacement, nan=0.0)  # a frame without a position: no measure
    straight = less_climbed(displacement, plan.interval_length_m, plan.interval_run_m)
    ran = straight / plan.interval_running_s
    length = np.nan_to_num(plan.interval_run_m, nan=0.0)
    zigzag = np.clip(
        np.where(straight > 0.05, length / np.maximum(straight, 1e-9), 1.0), 1.0, MAX_ZIGZAG
    )
    return np.maximum(plan.interval_max_speed_m_s, ran) * zigzag


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
