"""Timed waypoint plans: one player's snapped waypoints joined by shortest paths, with deadlines.

A plan says which waypoint the agent must reach by each data-frame time (a *target*), the full
node path between targets (weighted shortest paths on the directed graph), the same path as the
paper's action space (8 compass moves, one per edge, and STOP for waiting), and for every interval
between two targets how fast the player would have to run and whether that is possible with the
weapon in hand. Nothing is collapsed: standing still for 10 s is 10 s of STOP.

How a simulator executes a plan (the contract this module promises):

* Spawn the agent at `target_node[0]` at `target_seconds[0]`.
* Take the actions in order. A move crosses the edge `action_edge` to `action_node`; over one
  interval the agent runs at the interval's required speed, capped by `interval_max_speed_m_s`,
  so it reaches the target by its deadline unless the interval is `infeasible`. A STOP holds the
  agent at `action_node` until `action_deadline_s` (its planned length is `action_duration_s`; an
  agent that arrives late after an infeasible interval waits less, so it catches up with the
  clock instead of drifting).
* A RELOCATE marks an `unreachable` interval (the target cannot be reached from the previous
  waypoint on the directed graph: a gap in the graph; or, `bridged`, the graph's way is one the
  player cannot have taken). The agent holds its waypoint until the player crossed
  (`interval_cross_s`, at the latest the deadline), then is placed at `action_node` so that it
  stands there at that tick; the simulator counts it as a recovery, like a teleport out of a
  stuck position.
* After the last target the agent holds its waypoint. A plan never kills its agent: a player
  alive at the end of the data survives (`death_frame == -1`). A player who died in the data has
  `death_frame >= 0`, the first frame where the data shows it dead; a movement-only replay removes
  the agent at `death_seconds`, a replay with combat lets combat decide.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pandas as pd

from decoy_cli.errors import EstaError, GraphError
from decoy_cli.replay.pace import asks_more, edge_durations, less_climbed, running_seconds
from decoy_cli.waypoints.graph import DIRECTION_NAMES, STOP_ACTION, WaypointGraph
from decoy_cli.weapons import max_speed_m_s

RELOCATE_ACTION = 9
"""Plan-only action (not one of the paper's 9): jump to a waypoint across a gap in the graph."""

ACTION_NAMES = (*DIRECTION_NAMES, "STOP", "RELOCATE")
"""Display name of every plan action code: 0..7 compass moves, 8 STOP, 9 RELOCATE."""

_NO_EDGE = np.array([-1], dtype=np.int64)
"""The action list of an interval without a move (a STOP or a RELOCATE): no edge."""


class PathCache:
    """Shortest paths between waypoint pairs on one graph, each pair computed once; between the
    two ends of a ladder, the ladder (a player at one end and then the other climbed it, even
    where a drop beside it is quicker).

    Share one cache between the players of a round (or many rounds): players crossing the same
    spots ask for the same pairs.
    """

    def __init__(self, graph: WaypointGraph) -> None:
        self.graph = graph
        self._paths: dict[tuple[int, int], np.ndarray | None] = {}

    def __len__(self) -> int:
        """Number of (source, target) pairs computed so far."""
        return len(self._paths)

    def edges(self, source: int, target: int) -> np.ndarray | None:
        """Edge indices of the shortest path from `source` to `target`, None if unreachable.

        Empty for `source == target`.
        """
        key = (source, target)
        if key not in self._paths:
            self._paths[key] = self._compute(source, target)
        return self._paths[key]

    def _compute(self, source: int, target: int) -> np.ndarray | None:
        ladder = self.graph.ladder_between.get((source, target))
        if ladder is not None:
            return np.array([ladder], dtype=np.int64)  # from one end to the other: on it
        try:
            nodes = np.asarray(self.graph.shortest_path(source, target), dtype=np.int64)
        except GraphError:
            return None
        return self.graph.edges_between(nodes[:-1], nodes[1:])


@dataclass(frozen=True)
class PlayerPlan:
    """Timed plan of one player in one round; see the module docstring for how to execute it.

    Arrays come in four groups: targets (T,), intervals between consecutive targets (T-1,), the
    node path (K,) and the actions (A,). Times are seconds since freeze-time end, lengths metres.
    """

    target_frame: np.ndarray
    """(T,) int64 data frame of each target: alive and snapped frames, in order."""
    target_node: np.ndarray
    """(T,) int64 waypoint to be at by the target's deadline."""
    target_seconds: np.ndarray
    """(T,) float64 deadline of each target: its frame time."""
    target_path_index: np.ndarray
    """(T,) int64 position of each target in `path_node`."""

    interval_seconds: np.ndarray
    """(T-1,) float64 time from target k to target k+1."""
    interval_skipped_frames: np.ndarray
    """(T-1,) int64 frames between the two targets without a target (absent, unsnappable)."""
    interval_length_m: np.ndarray
    """(T-1,) float64 shortest-path length, 0 when standing still, NaN when unreachable."""
    interval_run_m: np.ndarray
    """(T-1,) float64 the part of it run at the player's own speed (`graph.edge_run_m`): all of
    it but the ladders, whose climb is counted in time (`interval_air_s`)."""
    interval_air_s: np.ndarray
    """(T-1,) float64 seconds of the path spent rising, falling or climbing a ladder
    (`graph.edge_fixed_s`)."""
    interval_required_speed_m_s: np.ndarray
    """(T-1,) float64 run length / running time (the time less the air time, at least a tick):
    the speed needed to arrive on time."""
    interval_max_speed_m_s: np.ndarray
    """(T-1,) float64 CS:GO maximum speed with the weapon held at the interval's start."""
    interval_speed_ratio: np.ndarray
    """(T-1,) float64 required / maximum speed (NaN when unreachable)."""
    interval_infeasible: np.ndarray
    """(T-1,) bool the ratio exceeds 1: the plan asks for more than the player can run."""
    interval_unreachable: np.ndarray
    """(T-1,) bool the target is not reachable from the previous one: the plan relocates."""
    interval_detour: np.ndarray
    """(T-1,) bool infeasible only by the graph's way: the straight line between the two
    waypoints would be run in time; infeasible and not this, the player was faster than its
    weapon's maximum even straight."""
    interval_zigzag: np.ndarray
    """(T-1,) bool a detour no longer than the lattice's zig-zag allows (`ZIGZAG_MAX`); the other
    detours go round something (a missing edge, a wall the player got past)."""
    interval_straight_m: np.ndarray
    """(T-1,) float64 straight-line distance between the interval's two waypoints."""
    interval_cross_s: np.ndarray
    """(T-1,) float64 when the agent of an unreachable interval is placed on its target: the
    first frame between the two targets where the player is nearer the target's waypoint than
    the start's (`build_plan`'s `positions`), else the deadline; NaN for the other intervals."""

    path_node: np.ndarray
    """(K,) int64 every waypoint in order; a repeated node is a wait or a relocation target."""
    path_interval: np.ndarray
    """(K,) int64 interval each entry ends, -1 for the start node."""
    path_deadline_s: np.ndarray
    """(K,) float64 deadline of the target whose interval holds the entry."""

    action: np.ndarray
    """(A,) int8 0..7 compass move (the edge's direction), 8 STOP, 9 RELOCATE."""
    action_edge: np.ndarray
    """(A,) int64 edge crossed by a move, -1 for STOP and RELOCATE."""
    action_node: np.ndarray
    """(A,) int64 waypoint the agent is at after the action."""
    action_interval: np.ndarray
    """(A,) int64 interval the action belongs to."""
    action_duration_s: np.ndarray
    """(A,) float64 planned duration: a move's share of its interval, a STOP's whole interval."""
    action_deadline_s: np.ndarray
    """(A,) float64 deadline of the action's interval."""

    last_alive_frame: int
    """Last frame the player is alive in the data, -1 if never."""
    death_frame: int
    """First frame after `last_alive_frame` that shows the player dead; -1 if it survives."""
    death_seconds: float
    """Frame time of `death_frame`, NaN if the player survives."""

    @property
    def is_empty(self) -> bool:
        """No target at all: the player is never alive on the graph."""
        return len(self.target_frame) == 0

    @property
    def died(self) -> bool:
        """The data shows the player dead after its last alive frame."""
        return self.death_frame >= 0

    @property
    def interval_running_s(self) -> np.ndarray:
        """(T-1,) float64 each interval's running time: its time less its path's air time, at
        least a tick (`running_seconds`); the required speed is the run length over it."""
        return running_seconds(self.interval_seconds, self.interval_air_s)

    @property
    def interval_straight_run_m(self) -> np.ndarray:
        """(T-1,) float64 the straight line between the targets less the ladders climbed on the
        way (at least 0): the distance the player's own speed must cover, as `interval_run_m`
        is the path's."""
        return less_climbed(self.interval_straight_m, self.interval_length_m, self.interval_run_m)

    @property
    def num_intervals(self) -> int:
        return len(self.interval_seconds)

    @property
    def num_infeasible(self) -> int:
        return int(np.count_nonzero(self.interval_infeasible))

    @property
    def num_unreachable(self) -> int:
        return int(np.count_nonzero(self.interval_unreachable))

    @property
    def worst_ratio(self) -> float:
        """Largest required / maximum speed ratio over reachable intervals, NaN if none."""
        ratios = self.interval_speed_ratio[~self.interval_unreachable]
        return float(ratios.max()) if len(ratios) else float("nan")

    @property
    def total_length_m(self) -> float:
        """Path length over all reachable intervals."""
        return float(np.nansum(self.interval_length_m))

    @property
    def stop_seconds(self) -> float:
        """Planned time spent in STOP actions."""
        return float(self.action_duration_s[self.action == STOP_ACTION].sum())

    def interval_table(self) -> pd.DataFrame:
        """One row per interval, for reports: frames, times, nodes, length, speeds and flags."""
        return pd.DataFrame(
            {
                "start_frame": self.target_frame[:-1],
                "end_frame": self.target_frame[1:],
                "start_s": self.target_seconds[:-1],
                "end_s": self.target_seconds[1:],
                "seconds": self.interval_seconds,
                "skipped_frames": self.interval_skipped_frames,
                "from_node": self.target_node[:-1],
                "to_node": self.target_node[1:],
                "length_m": self.interval_length_m,
                "required_m_s": self.interval_required_speed_m_s,
                "max_m_s": self.interval_max_speed_m_s,
                "ratio": self.interval_speed_ratio,
                "infeasible": self.interval_infeasible,
                "unreachable": self.interval_unreachable,
                "detour": self.interval_detour,
                "zigzag": self.interval_zigzag,
            }
        )


def build_plan(
    graph: WaypointGraph,
    snapped_nodes: np.ndarray,
    frame_seconds: np.ndarray,
    alive: np.ndarray,
    weapons: np.ndarray,
    *,
    present: np.ndarray | None = None,
    paths: PathCache | None = None,
    bridged: np.ndarray | None = None,
    positions: np.ndarray | None = None,
) -> PlayerPlan:
    """Build the timed plan of one player from its snapped waypoints (all arrays (F,)).

    `snapped_nodes` holds -1 for frames without a waypoint; `weapons` the weapon name in hand per
    frame ("" = none, runs at knife speed; an unknown name raises EstaError). `present` marks the
    frames where the player is recorded at all (default: every frame); after the last alive frame
    only a present, not-alive frame counts as a death, so a player who merely vanishes from the
    data is not killed. Frames without a target in the middle are joined over, with the deadline
    at the next target. `paths` shares a path cache between calls. `bridged` (F,) marks targets
    the plan reaches across a gap (a RELOCATE) although the graph has a way: a way the player
    did not take (`decoy_cli.replay.rounds.plan_player` says when). `positions` (F, 3), the
    player's real ones (NaN where absent), say when the player crossed a gap (`interval_cross_s`).
    """
    nodes = np.asarray(snapped_nodes, dtype=np.int64)
    seconds = np.asarray(frame_seconds, dtype=np.float64)
    alive = np.asarray(alive, dtype=bool)
    weapons = np.asarray(weapons)
    present = np.ones(len(seconds), dtype=bool) if present is None else np.asarray(present, bool)
    bridged = np.zeros(len(seconds), dtype=bool) if bridged is None else np.asarray(bridged, bool)
    frames = len(seconds)
    for name, array in (
        ("snapped nodes", nodes),
        ("alive flags", alive),
        ("weapons", weapons),
        ("present flags", present),
        ("bridged flags", bridged),
    ):
        if array.shape != (frames,):
            raise EstaError(f"{name} have shape {array.shape}, expected ({frames},)")
    if frames and (nodes.min() < -1 or nodes.max() >= graph.num_nodes):
        raise GraphError(f"snapped waypoints outside the graph's {graph.num_nodes} waypoints")
    if not np.all(np.isfinite(seconds)) or np.any(np.diff(seconds) < 0):
        raise EstaError("frame times must be finite and non-decreasing")
    if paths is None:
        paths = PathCache(graph)
    elif paths.graph is not graph:
        raise GraphError("the path cache belongs to another waypoint graph")

    target_frame = np.flatnonzero((nodes >= 0) & alive)
    target_node = nodes[target_frame]
    target_seconds = seconds[target_frame]
    interval_seconds = np.diff(target_seconds)
    count = len(interval_seconds)
    max_speed = _max_speeds(weapons[target_frame[:-1]])

    # Every interval's actions in one array: the edges of its shortest path, or one STOP (the
    # same waypoint) or RELOCATE (unreachable) with no edge (-1).
    sources, ends = target_node[:-1], target_node[1:]
    across = bridged[target_frame[1:]]
    found = [
        paths.edges(a, b) if a != b and not gap else None
        for a, b, gap in zip(sources.tolist(), ends.tolist(), across.tolist(), strict=True)
    ]
    unreachable = np.array([e is None for e in found], dtype=bool) & (sources != ends)
    steps = np.array([1 if e is None else len(e) for e in found], dtype=np.int64)
    action_edge = _concat([_NO_EDGE if e is None else e for e in found], np.int64)
    action_interval = np.repeat(np.arange(count, dtype=np.int64), steps)
    on_edge = action_edge >= 0
    edge = np.where(on_edge, action_edge, 0)
    edge_run = np.where(on_edge, graph.edge_run_m[edge], 0.0)  # run at the agent's speed
    edge_air = np.where(on_edge, graph.edge_fixed_s[edge], 0.0)  # rising, falling, climbing
    starts = np.cumsum(steps) - steps
    length, run, air = (
        _interval_sums(np.where(on_edge, graph.edge_length[edge], 0.0), starts, steps),
        _interval_sums(edge_run, starts, steps),
        _interval_sums(edge_air, starts, steps),
    )
    step_nodes = np.where(on_edge, graph.edge_target[edge], ends[action_interval])
    action = np.where(
        on_edge,
        graph.edge_direction[edge],
        np.where(unreachable[action_interval], RELOCATE_ACTION, STOP_ACTION),
    ).astype(np.int8)
    durations = edge_durations(
        interval_seconds[action_interval], edge_run, edge_air, run[action_interval],
        air[action_interval], on_edge,
    )  # fmt: skip
    length[unreachable] = np.nan
    run[unreachable] = np.nan

    with np.errstate(divide="ignore", invalid="ignore"):
        running = running_seconds(interval_seconds, air)
        required = np.where(run == 0, 0.0, run / running)
    ratio = required / max_speed
    straight = np.linalg.norm(
        graph.positions[target_node[1:]] - graph.positions[target_node[:-1]], axis=1
    )
    straight_run = less_climbed(straight, length, run)
    infeasible, detour, zigzag = asks_more(required, straight_run, running, run, max_speed)
    path_interval = np.concatenate([np.full(len(target_node[:1]), -1), action_interval])
    target_path_index = np.concatenate([[0], np.cumsum(steps)])[: len(target_node)]
    last_alive_frame, death_frame = _fate(alive, present)
    return PlayerPlan(
        target_frame=target_frame.astype(np.int64),
        target_node=target_node,
        target_seconds=target_seconds,
        target_path_index=target_path_index,
        interval_seconds=interval_seconds,
        interval_skipped_frames=np.diff(target_frame).astype(np.int64) - 1,
        interval_length_m=length,
        interval_run_m=run,
        interval_air_s=air,
        interval_required_speed_m_s=required,
        interval_max_speed_m_s=max_speed,
        interval_speed_ratio=ratio,
        interval_infeasible=infeasible,
        interval_unreachable=unreachable,
        interval_detour=detour,
        interval_zigzag=zigzag,
        interval_straight_m=straight,
        interval_cross_s=_crossings(
            graph, target_frame, target_node, seconds, unreachable, positions
        ),
        path_node=np.concatenate([target_node[:1], step_nodes]).astype(np.int64),
        path_interval=path_interval,
        path_deadline_s=target_seconds[path_interval + 1],
        action=action,
        action_edge=action_edge,
        action_node=step_nodes.astype(np.int64),
        action_interval=action_interval,
        action_duration_s=durations,
        action_deadline_s=target_seconds[action_interval + 1],
        last_alive_frame=last_alive_frame,
        death_frame=death_frame,
        death_seconds=float(seconds[death_frame]) if death_frame >= 0 else float("nan"),
    )


def _crossings(
    graph: WaypointGraph,
    target_frame: np.ndarray,
    target_node: np.ndarray,
    seconds: np.ndarray,
    unreachable: np.ndarray,
    positions: np.ndarray | None,
) -> np.ndarray:
    """`PlayerPlan.interval_cross_s` of every interval."""
    cross = np.full(len(unreachable), np.nan)
    for k in np.flatnonzero(unreachable).tolist():
        cross[k] = seconds[target_frame[k + 1]]
        if positions is None:
            continue
        between = np.arange(target_frame[k] + 1, target_frame[k + 1])
        where = np.asarray(positions, dtype=np.float64)[between]
        start, end = graph.positions[target_node[k]], graph.positions[target_node[k + 1]]
        with np.errstate(invalid="ignore"):
            nearer = np.linalg.norm(where - end, axis=1) < np.linalg.norm(where - start, axis=1)
        if nearer.any():
            cross[k] = seconds[between[int(np.argmax(nearer))]]
    return cross


def _max_speeds(names: np.ndarray) -> np.ndarray:
    """Maximum speed (m/s) for each weapon name, each distinct name looked up once."""
    unique, inverse = np.unique(names.astype(str), return_inverse=True)
    speeds = np.array([max_speed_m_s(str(name)) for name in unique], dtype=np.float64)
    return speeds[inverse]


def _fate(alive: np.ndarray, present: np.ndarray) -> tuple[int, int]:
    """(last alive frame, first later frame recorded dead), -1 where there is none."""
    alive_frames = np.flatnonzero(alive)
    if not len(alive_frames):
        return -1, -1
    last = int(alive_frames[-1])
    dead_after = np.flatnonzero(present[last + 1 :])
    return last, (last + 1 + int(dead_after[0])) if len(dead_after) else -1


def _concat(parts: list[np.ndarray], dtype: type) -> np.ndarray:
    """Concatenate per-interval arrays (none for a plan without intervals)."""
    return np.concatenate(parts).astype(dtype) if parts else np.zeros(0, dtype=dtype)


def _interval_sums(values: np.ndarray, starts: np.ndarray, steps: np.ndarray) -> np.ndarray:
    """The sum of each interval's run of `values`, rounded exactly as `ndarray.sum` rounds it:
    left to right for runs shorter than 8 (all runs at once, column by column), pairwise for
    longer ones (one at a time)."""
    short = np.minimum(steps, 7)
    columns = np.zeros((len(starts), 7))
    for j in range(7):
        has = short > j
        columns[has, j] = values[starts[has] + j]
    sums = columns[:, 0].copy()
    for j in range(1, 7):
        sums += columns[:, j]
    for k in np.flatnonzero(steps > 7).tolist():
        sums[k] = values[starts[k] : starts[k] + steps[k]].sum()
    return sums
