"""Snap many rounds and measure what their plans ask for: the numbers behind `decoy snap`.

For every round of a set of match files, every player is snapped and planned (`snap_round`).
The study keeps:

* `rows`: one row per player-round, the plan summary keyed by match, round, player and side;
* `intervals`: every frame interval that asks for more than the player's maximum speed or that
  crosses a gap in the graph, with what is needed to judge why (the original displacement and
  speed, the height change, the snap errors at both ends, the detour of the planned path, the
  nav places at both ends);
* the pooled snap errors of all snapped frames, summed up in `SnapTotals`.

With `metrics=True` the snapped-waypoint trajectory is compared with the original under both
protocols of docs/metrics.md: S_t is the position of the waypoint frame t snapped to, only where
it snapped; O_t the original position where the player is alive with a position. That is a first
bound on what a perfect replay on this graph can reach.

The files are read through the one round loop (`decoy_cli.esta.iter_matches`): a file or round
that cannot be read, a match of another map, or a round that cannot be snapped is recorded as a
`RoundFailure` with its one-line message and the rest go on.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np
import pandas as pd

from decoy_cli.errors import DecoyError, EstaError
from decoy_cli.esta import Match, Round, RoundFailure, each_round, iter_matches, match_rounds
from decoy_cli.metrics import METRIC_NAMES, MetricSummary, PlayerRound, summarize
from decoy_cli.metrics.trajectory import trajectory_metrics_frame
from decoy_cli.replay.rounds import RoundPlan, snap_round
from decoy_cli.replay.snapping import DEFAULT_MAX_SNAP_M, WITHIN_M, SnapStatus
from decoy_cli.waypoints.graph import WaypointGraph
from decoy_cli.world.physics import PhysicsWorld

KEY_COLUMNS = ("match", "round", "player", "side")
"""Columns that identify a player-round in `rows` and `intervals`."""

SEVERE_RATIO = 2.0
"""A speed ratio above this is more than snap noise can explain (twice the maximum speed)."""

INTERVAL_COLUMNS = (
    *KEY_COLUMNS,
    "start_frame",
    "end_frame",
    "start_s",
    "seconds",
    "skipped_frames",
    "weapon",
    "from_node",
    "to_node",
    "length_m",
    "snapped_straight_m",
    "detour",
    "original_straight_m",
    "original_m_s",
    "original_dz_m",
    "snapped_dz_m",
    "required_m_s",
    "max_m_s",
    "ratio",
    "start_error_m",
    "end_error_m",
    "from_place",
    "to_place",
    "unreachable",
)
"""Columns of `intervals`: one row per infeasible or unreachable interval.

`length_m` is the planned path, `snapped_straight_m` the straight 3-D distance between its two
waypoints and `detour` their ratio; `original_straight_m`, `original_m_s` and `original_dz_m`
are the straight distance, speed and height change between the original positions of the two
frames (an original speed above `max_m_s` means the player itself moved faster than the weapon's
running speed: a jump, a fall, a teleport or a glitch); `snapped_dz_m` is the height change
between the two waypoints (far from `original_dz_m`: a snap to another floor).
"""


@dataclass(frozen=True)
class SnapTotals:
    """Pooled snap quality and plan feasibility over a set of player-rounds."""

    rounds: int
    player_rounds: int
    frames_with_position: int
    """Alive frames with a position, on the ground when the world was given: snapped plus
    unsnappable."""
    snapped: int
    unsnappable: int
    airborne: int
    """Alive frames in the air (not snapped; counted only when the world was given)."""
    snap_median_m: float
    snap_p95_m: float
    within: float
    """Share of `frames_with_position` snapped within `WITHIN_M`."""
    intervals: int
    infeasible: int
    unreachable: int
    worst_ratio: float

    @property
    def infeasible_share(self) -> float:
        """Share of frame intervals that need more than the player's maximum speed."""
        return self.infeasible / self.intervals if self.intervals else float("nan")


@dataclass(frozen=True)
class RoundStudy:
    """The study of one round: its plan, its player rows, its bad intervals, its snap errors."""

    plan: RoundPlan
    rows: pd.DataFrame
    intervals: pd.DataFrame
    errors: np.ndarray
    """(M,) snap errors of every snapped frame of every player, metres."""

    @property
    def totals(self) -> SnapTotals:
        return pooled_totals(self.rows, self.errors, rounds=1)


@dataclass(frozen=True)
class SnapStudy:
    """The study of many rounds; see the module docstring."""

    rows: pd.DataFrame
    intervals: pd.DataFrame
    totals: SnapTotals
    failures: list[RoundFailure]
    metrics: MetricSummary | None
    """Aggregated fidelity metrics of the snapped trajectories (None without `metrics=True`)."""

    def worst(self, count: int = 10) -> pd.DataFrame:
        """The `count` reachable intervals with the largest speed ratio, largest first."""
        return worst_intervals(self.intervals, count)


def worst_intervals(intervals: pd.DataFrame, count: int = 10) -> pd.DataFrame:
    """The `count` reachable intervals of an `intervals` table with the largest speed ratio."""
    reachable = intervals[~intervals["unreachable"].astype(bool)]
    return reachable.sort_values("ratio", ascending=False, kind="stable").head(count)


def infeasible_by_place(intervals: pd.DataFrame, count: int = 10) -> pd.DataFrame:
    """Where the too-fast intervals are: the `count` (from, to) nav place pairs that hold most.

    Columns: from_place, to_place, intervals, share (of all too-fast intervals), severe (ratio
    above `SEVERE_RATIO`), median_ratio, worst_ratio, median_detour. Ordered by severe, then
    intervals: mild ratios are mostly snap noise, severe ones with a large detour point at a
    missing edge.
    """
    fast = intervals[~intervals["unreachable"].astype(bool)]
    columns = ["from_place", "to_place", "intervals", "share", "severe", "median_ratio"]
    if not len(fast):
        return pd.DataFrame(columns=[*columns, "worst_ratio", "median_detour"])
    fast = fast.assign(severe=fast["ratio"] > SEVERE_RATIO)
    table = (
        fast.groupby(["from_place", "to_place"], sort=False)
        .agg(
            intervals=("ratio", "size"),
            severe=("severe", "sum"),
            median_ratio=("ratio", "median"),
            worst_ratio=("ratio", "max"),
            median_detour=("detour", "median"),
        )
        .reset_index()
    )
    table.insert(3, "share", table["intervals"] / len(fast))
    table = table.sort_values(["severe", "intervals"], ascending=False, kind="stable")
    return table.head(count).reset_index(drop=True)


def check_map(match: Match, graph: WaypointGraph) -> None:
    """An EstaError when the match was played on another map than the graph's."""
    graph_map = str(graph.meta.get("map", ""))
    if match.map_name and graph_map and match.map_name != graph_map:
        raise EstaError(
            f"{match.path}: a {match.map_name} match cannot be snapped to the {graph_map} "
            "waypoint graph"
        )


SNAP_ERROR = "snap error"


def study_round(
    round_: Round,
    graph: WaypointGraph,
    *,
    metrics: bool = False,
    max_distance: float = DEFAULT_MAX_SNAP_M,
    physics: PhysicsWorld | None = None,
) -> RoundStudy:
    """Snap and plan one round (a reader `Round`) and gather its rows, intervals and errors.
    With `physics` (the graph's world), frames in the air are told apart and not snapped, as
    the replay does."""
    plan = snap_round(round_, graph, max_distance=max_distance, physics=physics)
    match_id, round_num = str(round_.match_id), int(round_.round_num)
    rows = plan.summary.copy()
    rows.insert(0, "round", round_num)
    rows.insert(0, "match", match_id)
    positions = np.asarray(round_.position, dtype=np.float64)
    if metrics:
        scores = trajectory_metrics_frame(
            _player_rounds(plan, positions, np.asarray(round_.alive, bool), graph)
        )
        rows = pd.concat([rows, scores[[*METRIC_NAMES, "reason"]]], axis=1)
    weapons = np.asarray(round_.weapon)
    parts = [
        _bad_intervals(plan, p, positions[p], weapons[p], graph) for p in range(len(plan.players))
    ]
    columns = {  # every column but match and round
        name: np.concatenate([part[name] for part in parts]) if parts else np.zeros(0)
        for name in INTERVAL_COLUMNS[2:]
    }
    count = len(columns["ratio"])
    table = pd.DataFrame(
        {
            "match": np.full(count, match_id, dtype=object),
            "round": np.full(count, round_num, dtype=np.int64),
            **columns,
        }
    )
    errors = [snap.error_m[snap.status == SnapStatus.SNAPPED] for snap in plan.snaps]
    return RoundStudy(
        plan=plan,
        rows=rows,
        intervals=table,
        errors=np.concatenate(errors) if errors else np.zeros(0),
    )


def study_files(
    files: Sequence[Path],
    graph: WaypointGraph,
    *,
    metrics: bool = False,
    max_distance: float = DEFAULT_MAX_SNAP_M,
    on_progress: Callable[[float, int], None] | None = None,
    physics: PhysicsWorld | None = None,
    rate: float | None = None,
) -> SnapStudy:
    """Study every round of every match file; failures are recorded, the batch goes on.
    `physics` as in `study_round`; `rate` the frames a second read from awpy's ticks.

    `on_progress(files_done, rounds_studied)` is called after each round and after each file;
    `files_done` counts a file's rounds as fractions of it (1.5 = half of the second file).
    """
    studies: list[RoundStudy] = []
    failures: list[RoundFailure] = []
    graph_map = str(graph.meta.get("map", "")) or None
    for i, item in enumerate(iter_matches(files, map_name=graph_map, rate=rate)):
        if isinstance(item, RoundFailure):
            failures.append(item)
        else:
            _study_match(item, graph, (metrics, max_distance, physics), studies, failures, i,
                         on_progress)  # fmt: skip
        if on_progress is not None:
            on_progress(i + 1.0, len(studies))
    return combine(studies, failures, metrics=metrics)


def _study_match(
    match: Match,
    graph: WaypointGraph,
    how: tuple[bool, float, PhysicsWorld | None],
    studies: list[RoundStudy],
    failures: list[RoundFailure],
    index: int,
    on_progress: Callable[[float, int], None] | None,
) -> None:
    """Study the rounds of one match into `studies`, recording the ones that fail; `how` is
    (metrics, max_distance, physics) as `study_round` takes them."""
    metrics, max_distance, physics = how
    count = len(match.rounds)  # progress counts the rounds the reader built
    built = 0

    def study(round_: Round) -> RoundStudy:
        return study_round(
            round_, graph, metrics=metrics, max_distance=max_distance, physics=physics
        )

    for item in each_round(match_rounds(match), study, SNAP_ERROR, catch=DecoyError):
        if isinstance(item, RoundFailure) and item.kind != SNAP_ERROR:
            failures.append(item)  # the reader's: not a round that progress counts
            continue
        built += 1
        if isinstance(item, RoundFailure):
            prefix = f"{match.path}: round {item.round_num}: "
            failures.append(replace(item, message=prefix + item.message))
        else:
            studies.append(item[1])
        if on_progress is not None:
            on_progress(index + built / count, len(studies))


def combine(
    studies: list[RoundStudy], failures: list[RoundFailure] | None = None, *, metrics: bool = False
) -> SnapStudy:
    """Join round studies into one; with `metrics`, aggregate the metrics by side."""
    if studies:
        rows = pd.concat([s.rows for s in studies], ignore_index=True)
        parts = [s.intervals for s in studies if len(s.intervals)]
        intervals = (
            pd.concat(parts, ignore_index=True) if parts else studies[0].intervals.iloc[:0].copy()
        )
        errors = np.concatenate([s.errors for s in studies])
    else:
        rows = pd.DataFrame(columns=list(KEY_COLUMNS))
        intervals = pd.DataFrame(columns=list(INTERVAL_COLUMNS))
        errors = np.zeros(0)
    summary = None
    if metrics:
        if "reason" not in rows.columns:
            rows = rows.reindex(columns=[*rows.columns, *METRIC_NAMES, "reason"])
        summary = summarize(rows)
    return SnapStudy(
        rows=rows,
        intervals=intervals,
        totals=pooled_totals(rows, errors, rounds=len(studies)),
        failures=list(failures or []),
        metrics=summary,
    )


def pooled_totals(rows: pd.DataFrame, errors: np.ndarray, *, rounds: int) -> SnapTotals:
    """Totals over player-round rows (plan summary columns) and their pooled snap errors."""
    unsnappable = int(rows["unsnappable"].sum()) if len(rows) else 0
    with_position = len(errors) + unsnappable
    if len(errors):
        median, p95 = (float(v) for v in np.percentile(errors, [50, 95]))
    else:
        median = p95 = float("nan")
    ratios = rows["worst_ratio"].to_numpy(dtype=np.float64) if len(rows) else np.zeros(0)
    return SnapTotals(
        rounds=rounds,
        player_rounds=len(rows),
        frames_with_position=with_position,
        snapped=len(errors),
        unsnappable=unsnappable,
        airborne=int(rows["airborne"].sum()) if len(rows) and "airborne" in rows else 0,
        snap_median_m=median,
        snap_p95_m=p95,
        within=(
            float(np.count_nonzero(errors <= WITHIN_M) / with_position)
            if with_position
            else float("nan")
        ),
        intervals=int(rows["intervals"].sum()) if len(rows) else 0,
        infeasible=int(rows["infeasible"].sum()) if len(rows) else 0,
        unreachable=int(rows["unreachable"].sum()) if len(rows) else 0,
        worst_ratio=float(np.nanmax(ratios)) if np.isfinite(ratios).any() else float("nan"),
    )


def _player_rounds(
    plan: RoundPlan, positions: np.ndarray, alive: np.ndarray, graph: WaypointGraph
) -> list[PlayerRound]:
    """Original versus snapped-waypoint trajectory of every player of the round."""
    items = []
    for p, (player, snap) in enumerate(zip(plan.players, plan.snaps, strict=True)):
        snapped = snap.status == SnapStatus.SNAPPED
        simulated = np.full(positions[p].shape, np.nan)
        simulated[snapped] = graph.positions[snap.node[snapped]]
        items.append(
            PlayerRound(
                key={"player": str(player.name)},
                original=positions[p],
                original_alive=alive[p] & np.isfinite(positions[p]).all(axis=1),
                simulated=simulated,
                simulated_alive=snapped,
            )
        )
    return items


def _bad_intervals(
    plan: RoundPlan, p: int, positions: np.ndarray, weapons: np.ndarray, graph: WaypointGraph
) -> dict[str, np.ndarray]:
    """The `INTERVAL_COLUMNS` but match and round of player `p`'s too-fast and gap intervals."""
    player, snap, player_plan = plan.players[p], plan.snaps[p], plan.plans[p]
    bad = np.flatnonzero(player_plan.interval_infeasible | player_plan.interval_unreachable)
    start, end = player_plan.target_frame[bad], player_plan.target_frame[bad + 1]
    from_node, to_node = player_plan.target_node[bad], player_plan.target_node[bad + 1]
    seconds = player_plan.interval_seconds[bad]
    length = player_plan.interval_length_m[bad]
    snapped_straight = np.linalg.norm(graph.positions[to_node] - graph.positions[from_node], axis=1)
    original_straight = np.linalg.norm(positions[end] - positions[start], axis=1)
    with np.errstate(divide="ignore", invalid="ignore"):
        detour = length / snapped_straight
        original_speed = original_straight / seconds
    # node_place -1 (no place) indexes the trailing "".
    places = np.array([*graph.place_names, ""], dtype=object)
    return {
        "player": np.full(len(bad), str(player.name), dtype=object),
        "side": np.full(len(bad), str(player.side), dtype=object),
        "start_frame": start,
        "end_frame": end,
        "start_s": player_plan.target_seconds[bad],
        "seconds": seconds,
        "skipped_frames": player_plan.interval_skipped_frames[bad],
        "weapon": weapons[start].astype(object),
        "from_node": from_node,
        "to_node": to_node,
        "length_m": length,
        "snapped_straight_m": snapped_straight,
        "detour": detour,
        "original_straight_m": original_straight,
        "original_m_s": original_speed,
        "original_dz_m": positions[end, 2] - positions[start, 2],
        "snapped_dz_m": graph.positions[to_node, 2] - graph.positions[from_node, 2],
        "required_m_s": player_plan.interval_required_speed_m_s[bad],
        "max_m_s": player_plan.interval_max_speed_m_s[bad],
        "ratio": player_plan.interval_speed_ratio[bad],
        "start_error_m": snap.error_m[start],
        "end_error_m": snap.error_m[end],
        "from_place": places[graph.node_place[from_node]],
        "to_place": places[graph.node_place[to_node]],
        "unreachable": player_plan.interval_unreachable[bad],
    }
