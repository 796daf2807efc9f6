"""Top-down picture of a snapped round: original positions, their waypoints, the planned paths.

Drawn over the nav areas (the walkable map) and the graph's edges (faint, so a missing edge or a
detour shows). Per player, in its own colour: the original positions (dots joined by a thin
dashed line), the waypoint each frame snapped to (crosses, tied to their position by a grey
segment: the snap error), and the planned path through the waypoints (solid). Intervals that ask
for more than the player's maximum speed are drawn red on top, intervals across a gap in the
graph as a black dashed jump, and alive frames that could not be snapped as hollow red circles.
The view is zoomed on the positions and waypoints drawn (a long detour leaves the view, which is
itself the sign of a missing edge); a frame window restricts the picture to part of the round.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

import numpy as np

from decoy_cli.figures import draw_nav_areas, save_figure
from decoy_cli.replay.plans import PlayerPlan
from decoy_cli.replay.rounds import RoundPlan
from decoy_cli.replay.snapping import SnapStatus
from decoy_cli.waypoints.graph import WaypointGraph
from decoy_cli.world.navmesh import NavMesh

MARGIN_M = 4.0
"""Space around the drawn data, metres."""
MIN_SPAN_M = 20.0
"""Smallest side of the view, metres, so a short window still shows its surroundings."""


def plot_round_plan(
    plan: RoundPlan,
    positions: np.ndarray,
    graph: WaypointGraph,
    path: str | Path,
    *,
    nav: NavMesh | None = None,
    players: Sequence[int] | None = None,
    frames: tuple[int, int] | None = None,
    title: str = "",
    dpi: int = 150,
) -> None:
    """Write a PNG of the snapped round; `positions` is the round's (P, F, 3) array in metres.

    `players` are row indices to draw (default all); `frames` an inclusive (first, last) window
    of data frames (default the whole round): targets and path parts of intervals that end
    inside it are drawn.
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.collections import LineCollection

    positions = np.asarray(positions, dtype=np.float64)
    rows = range(len(plan.players)) if players is None else players
    first, last = frames if frames is not None else (0, len(plan.frame_seconds) - 1)

    fig, ax = plt.subplots(figsize=(12, 12))
    if nav is not None:
        draw_nav_areas(ax, nav, facecolor="#ececec")
    pos = graph.positions
    edges = np.stack([pos[graph.edge_source, :2], pos[graph.edge_target, :2]], axis=1)
    # The collections' stubs want a Sequence of lines; an (N, 2, 2) array is one to matplotlib.
    ax.add_collection(LineCollection(edges, colors="#c4c4c4", lw=0.25, zorder=1))  # type: ignore[arg-type]

    # tab10 without its red, which marks the intervals that are too fast.
    colours = [c for i, c in enumerate(matplotlib.color_sequences["tab10"]) if i != 3]
    drawn: list[np.ndarray] = []
    for n, p in enumerate(rows):
        colour = colours[n % len(colours)]
        snap, player_plan = plan.snaps[p], plan.plans[p]
        window = np.zeros(len(plan.frame_seconds), dtype=bool)
        window[first : last + 1] = True
        with_position = window & (snap.status != SnapStatus.NOT_ALIVE)
        with_position &= snap.status != SnapStatus.NO_POSITION
        snapped = window & (snap.status == SnapStatus.SNAPPED)
        original = positions[p, with_position, :2]
        waypoint = pos[snap.node[snapped], :2]
        drawn.extend([original, waypoint])
        name = f"{plan.players[p].name} ({plan.players[p].side})"
        ax.plot(*original.T, ls="--", lw=0.6, color=colour, zorder=3)
        ax.scatter(
            original[:, 0], original[:, 1], s=9, color=colour, zorder=4, label=f"{name}: original"
        )
        ax.scatter(waypoint[:, 0], waypoint[:, 1], s=22, marker="x", lw=0.9, color=colour, zorder=5)
        ax.add_collection(
            LineCollection(
                np.stack([positions[p, snapped, :2], waypoint], axis=1),  # type: ignore[arg-type]
                colors="#555555",
                lw=0.5,
                zorder=4,
            )
        )
        lost = positions[p, window & (snap.status == SnapStatus.NO_WAYPOINT), :2]
        ax.scatter(
            lost[:, 0], lost[:, 1], s=60, facecolors="none", edgecolors="#d62728", lw=1.2, zorder=6
        )
        drawn.append(lost)

        if player_plan.is_empty:
            continue
        ends = player_plan.target_frame[1:]
        shown = (ends >= first) & (ends <= last) & ~player_plan.interval_unreachable
        ax.add_collection(
            LineCollection(
                _path_segments(player_plan, shown, pos),  # type: ignore[arg-type]
                colors=[colour],
                lw=1.6,
                alpha=0.75,
                zorder=2,
            )
        )
        ax.add_collection(
            LineCollection(
                _path_segments(  # type: ignore[arg-type]
                    player_plan, shown & player_plan.interval_infeasible, pos
                ),
                colors="#d62728",
                lw=2.4,
                zorder=7,
            )
        )
        gaps = np.flatnonzero((ends >= first) & (ends <= last) & player_plan.interval_unreachable)
        for k in gaps:
            a, b = player_plan.target_node[k], player_plan.target_node[k + 1]
            ax.plot(*pos[[a, b], :2].T, color="black", ls=(0, (3, 2)), lw=1.4, zorder=7)
        start = player_plan.target_frame[0]
        if first <= start <= last:
            ax.scatter(
                positions[p, start, 0],
                positions[p, start, 1],
                marker="^",
                s=70,
                color=colour,
                edgecolors="black",
                zorder=8,
            )
        if player_plan.died and first <= player_plan.last_alive_frame <= last:
            ax.scatter(
                positions[p, player_plan.last_alive_frame, 0],
                positions[p, player_plan.last_alive_frame, 1],
                marker="X",
                s=90,
                color=colour,
                edgecolors="black",
                zorder=8,
            )

    ax.plot([], [], color="#d62728", lw=2.4, label="needs more than max speed")
    ax.plot([], [], color="black", ls=(0, (3, 2)), lw=1.4, label="unreachable (relocate)")
    ax.scatter([], [], s=60, facecolors="none", edgecolors="#d62728", label="not snapped")
    ax.scatter([], [], marker="x", color="#555555", label="snapped waypoint")
    _zoom(ax, drawn)
    ax.set_aspect("equal")
    ax.set_xlabel("x (m, east)")
    ax.set_ylabel("y (m, north)")
    ax.legend(loc="best", fontsize=8)
    ax.set_title(title)
    save_figure(fig, path, dpi)


def _path_segments(plan: PlayerPlan, chosen: np.ndarray, pos: np.ndarray) -> np.ndarray:
    """(S, 2, 2) x-y segments of the planned path inside the chosen intervals.

    Path entry e > 0 is reached during interval `path_interval[e]`, so the segment from entry
    e - 1 to e belongs to that interval.
    """
    nodes = plan.path_node
    keep = chosen[plan.path_interval[1:]] & (nodes[:-1] != nodes[1:])
    return np.stack([pos[nodes[:-1][keep], :2], pos[nodes[1:][keep], :2]], axis=1).reshape(-1, 2, 2)


def _zoom(ax, drawn: list[np.ndarray]) -> None:
    """Fit the view to the drawn points, with a margin and a minimum span."""
    points = np.concatenate([d.reshape(-1, 2) for d in drawn]) if drawn else np.zeros((0, 2))
    if not len(points):
        ax.autoscale_view()
        return
    low, high = points.min(axis=0) - MARGIN_M, points.max(axis=0) + MARGIN_M
    centre, half = (low + high) / 2, np.maximum((high - low) / 2, MIN_SPAN_M / 2)
    ax.set_xlim(centre[0] - half[0], centre[0] + half[0])
    ax.set_ylim(centre[1] - half[1], centre[1] + half[1])
