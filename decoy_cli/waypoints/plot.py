"""Top-down picture of a waypoint graph over the walkable map.

Walk and step edges are coloured by height; jump edges and drop edges have their own colours so
they stand out; optionally, edges removed by verification and nodes removed by pruning are drawn
too, for looking at what the builder threw away.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from decoy_cli.figures import draw_nav_areas, save_figure
from decoy_cli.waypoints.graph import EdgeKind, WaypointGraph
from decoy_cli.world.navmesh import NavMesh


def plot_graph(
    graph: WaypointGraph,
    path: str | Path,
    nav: NavMesh | None = None,
    floor_triangles: np.ndarray | None = None,
    removed_segments: np.ndarray | None = None,
    pruned_positions: np.ndarray | None = None,
    title: str = "",
    dpi: int = 150,
) -> None:
    """Write a PNG of the graph. The walkable map is the nav areas or the given floor triangles."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.collections import LineCollection, PolyCollection

    fig, ax = plt.subplots(figsize=(12, 12))
    if nav is not None:
        draw_nav_areas(ax, nav)
    if floor_triangles is not None and len(floor_triangles):
        # The collections' stubs want a Sequence of polygons or lines; an array is one too.
        triangles = floor_triangles[:, :, :2]
        ax.add_collection(
            PolyCollection(triangles, facecolor="#e6e6e6", edgecolor="none")  # type: ignore[arg-type]
        )
    pos = graph.positions
    segments = np.stack([pos[graph.edge_source, :2], pos[graph.edge_target, :2]], axis=1)
    kind = graph.edge_kind
    flat = (kind == EdgeKind.WALK) | (kind == EdgeKind.STEP)
    height = (pos[graph.edge_source, 2] + pos[graph.edge_target, 2]) / 2
    lines = LineCollection(segments[flat], array=height[flat], cmap="viridis", lw=0.4)
    ax.add_collection(lines)
    fig.colorbar(lines, ax=ax, shrink=0.6, label="height (m)")
    # a ledge usually has a drop one way and a jump the other: draw the jump thinner on top
    ax.add_collection(
        LineCollection(segments[kind == EdgeKind.DROP], colors="#d62728", lw=2.4, label="drop")
    )
    ax.add_collection(
        LineCollection(segments[kind == EdgeKind.JUMP], colors="#ffbf00", lw=1.0, label="jump")
    )
    ladder = kind == EdgeKind.LADDER  # nearly vertical: a marker at each end, not a line
    if ladder.any():
        ends = pos[graph.edge_source[ladder]]
        ax.scatter(ends[:, 0], ends[:, 1], marker="^", s=36, c="#1f77b4", label="ladder", zorder=3)
    if removed_segments is not None and len(removed_segments):
        ax.add_collection(
            LineCollection(
                removed_segments[:, :, :2],  # type: ignore[arg-type]
                colors="#e377c2",
                lw=0.8,
                label="removed by verification",
            )
        )
    if pruned_positions is not None and len(pruned_positions):
        ax.scatter(
            pruned_positions[:, 0], pruned_positions[:, 1], s=2, c="#7f7f7f", label="pruned nodes"
        )
    ax.set_aspect("equal")
    ax.autoscale_view()
    ax.set_xlabel("x (m, east)")
    ax.set_ylabel("y (m, north)")
    ax.legend(loc="lower right")
    ax.set_title(title or f"{graph.num_nodes} waypoints, {graph.num_edges} edges")
    save_figure(fig, path, dpi)
