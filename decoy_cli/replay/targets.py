"""Which frames a player's plan targets and at which waypoint, whatever the data's frame rate.

Hard targets come no denser than the graph's lattice resolves (`target_seconds`, `hard_frames`);
a hard target whose waypoint makes the replay late may move to a neighbouring waypoint by the
player (`resnap`); an interval whose path the player cannot have taken is crossed as a gap
(`lacks_the_way`). `decoy_cli.replay.rounds.plan_player` applies them.
"""

from __future__ import annotations

import numpy as np

from decoy_cli.csgo import TICK_RATE
from decoy_cli.replay.pace import MAX_ZIGZAG, RATIO_TOLERANCE
from decoy_cli.replay.plans import PathCache, PlayerPlan
from decoy_cli.waypoints.graph import RUN_SPEED_M_S, WaypointGraph
from decoy_cli.waypoints.lattice_params import LatticeParams
from decoy_cli.waypoints.patch_check import LENGTHENED_EXTRA_M, LENGTHENED_RATIO


def lattice_spacing(graph: WaypointGraph) -> float:
    """The spacing of the lattice the graph was built on (metres; the builder's default when
    the graph does not say)."""
    params = graph.meta.get("params", {}) if isinstance(graph.meta, dict) else {}
    return float(params.get("spacing", LatticeParams().spacing))


def target_seconds(graph: WaypointGraph) -> float:
    """The shortest time between two hard targets the graph's lattice resolves: the lattice may
    put a path up to one spacing longer than the player's own displacement (snapping each end
    to a neighbouring waypoint), and the replay may outrun the player by `MAX_ZIGZAG`; a run at
    the knife's speed covers that spacing within the allowance only over this time or more."""
    return lattice_spacing(graph) / ((MAX_ZIGZAG - 1.0) * RUN_SPEED_M_S)


def hard_frames(seconds: np.ndarray, usable: np.ndarray, every_s: float) -> np.ndarray:
    """(F,) bool: the `usable` frames that are hard targets, the first one and then each first
    one at least `every_s` after the last (on the data's clock, so a frame rate that changes
    within the round is followed as it comes). At 2 frames per second or fewer every usable
    frame is hard."""
    hard = np.zeros(len(seconds), dtype=bool)
    last = -np.inf
    for f in np.flatnonzero(usable).tolist():
        if seconds[f] - last >= every_s - 1e-9:
            hard[f] = True
            last = float(seconds[f])
    return hard


def resnap(
    graph: WaypointGraph,
    plan: PlayerPlan,
    caps: np.ndarray,
    targets: np.ndarray,
    nodes: np.ndarray,
    positions: np.ndarray,
    error_m: np.ndarray,
    paths: PathCache,
) -> None:
    """Move each of a plan's `targets` (indices, in time order) to the nearest waypoint by its
    real position from which the replay keeps time with its neighbouring targets (the one
    before as already moved), running at the intervals' `caps`; where none does, to the one it
    is least late by, if less than its own (`nodes` (F,) is changed in place).

    A position lies between waypoints: every waypoint on its floor no farther from it than its
    snapped one plus half a spacing is as faithful within the lattice's resolution (a position
    on a waypoint has no other), and where snapping picked one that a wall, a door or a step
    separates from the player's way, such a neighbour keeps the replay on it."""
    spacing = lattice_spacing(graph)
    count = len(plan.target_node)
    seconds = plan.target_seconds

    def overrun(source: int, target: int, seconds: float, cap: float) -> float:
        """How much longer than `seconds` the path takes at `cap` (inf: unreachable)."""
        edges = paths.edges(source, target)
        if edges is None:
            return np.inf
        run = float(graph.edge_run_m[edges].sum())
        took = (run / cap if run > 0 else 0.0) + float(graph.edge_fixed_s[edges].sum())
        return max(0.0, took - seconds)

    for t in targets.tolist():
        if t == 0:
            continue  # the spawn: nothing leads to it
        frame = int(plan.target_frame[t])
        before = int(nodes[plan.target_frame[t - 1]])  # as moved already: in time order
        late = [(before, float(seconds[t] - seconds[t - 1]), float(caps[t - 1]), True)]
        if t + 1 < count:
            after = int(plan.target_node[t + 1])
            late.append((after, float(seconds[t + 1] - seconds[t]), float(caps[t]), False))

        def lateness(node: int, late: list = late) -> float:
            return sum(
                overrun(other, node, s, cap) if into else overrun(node, other, s, cap)
                for other, s, cap, into in late
            )

        near = graph.near(positions[frame], float(error_m[frame]) + spacing / 2)
        if not len(near):
            continue
        own = lateness(int(nodes[frame]))
        for node in near.tolist():
            if lateness(node) <= 1.0 / TICK_RATE:
                nodes[frame] = node
                break
        else:
            worst = [lateness(node) for node in near.tolist()]
            if min(worst) < own - 1e-9:
                nodes[frame] = int(near[int(np.argmin(worst))])


def lacks_the_way(plan: PlayerPlan, caps: np.ndarray, positions: np.ndarray) -> np.ndarray:
    """(T-1,) bool the intervals whose path the player cannot have taken: longer than
    `LENGTHENED_RATIO` times the player's own displacement plus `LENGTHENED_EXTRA_M` (a detour,
    as the learned patches' check counts one) and asking more than the cap. The player went a
    way the graph lacks (a staircase or a gap the map's version has and the graph's world does
    not, a teleport), and a replay sent round would fall behind and away from it."""
    if len(plan.target_node) < 2:
        return np.zeros(0, dtype=bool)
    displacement = np.linalg.norm(np.diff(positions[plan.target_frame], axis=0), axis=1)
    length = np.nan_to_num(plan.interval_length_m, nan=0.0)
    with np.errstate(invalid="ignore"):
        detour = length > LENGTHENED_RATIO * displacement + LENGTHENED_EXTRA_M
        over = plan.interval_required_speed_m_s > caps * (1.0 + RATIO_TOLERANCE)
    return detour & over & ~plan.interval_unreachable
