"""Line of sight between the waypoints of a graph: which pairs to compare, and where two worlds
disagree by nav place (decoy_cli/world/los.py compares the worlds themselves).

* `random_node_pairs` draws waypoint pairs (seeded, optionally within a combat distance) and
  `eye_pairs` lifts them to standing eye height, for `compare_line_of_sight`;
* `disagreement_by_place` counts the disagreements of a comparison by the pairs' nav places.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from decoy_cli.csgo import EYE_HEIGHT_M
from decoy_cli.errors import GraphError
from decoy_cli.geometry import eye_point
from decoy_cli.waypoints.graph import WaypointGraph
from decoy_cli.world.los import LosComparison

_MAX_DRAW_ROUNDS = 200


def random_node_pairs(
    graph: WaypointGraph,
    count: int,
    seed: int = 0,
    max_distance: float | None = None,
    min_distance: float = 0.0,
) -> np.ndarray:
    """(count, 2) indices of distinct random waypoints, uniformly over the ordered pairs whose
    3-D distance lies in [min_distance, max_distance] (metres); the same seed gives the same
    pairs. A GraphError when such pairs are too rare to find."""
    if count < 0:
        raise GraphError(f"cannot draw {count} pairs")
    if graph.num_nodes < 2:
        raise GraphError(f"a graph of {graph.num_nodes} waypoints has no pairs")
    upper = np.inf if max_distance is None else max_distance
    rng = np.random.default_rng(seed)
    found: list[np.ndarray] = []
    have = 0
    batch = max(4 * count, 1024)
    for _ in range(_MAX_DRAW_ROUNDS):
        if have >= count:
            break
        nodes = rng.integers(0, graph.num_nodes, size=(batch, 2))
        dist = np.linalg.norm(graph.positions[nodes[:, 0]] - graph.positions[nodes[:, 1]], axis=1)
        keep = (nodes[:, 0] != nodes[:, 1]) & (dist >= min_distance) & (dist <= upper)
        found.append(nodes[keep])
        have += int(keep.sum())
    if have < count:
        raise GraphError(
            f"found only {have} of {count} waypoint pairs between {min_distance:g} m and "
            f"{upper:g} m apart in {_MAX_DRAW_ROUNDS * batch:,} draws"
        )
    return np.concatenate(found)[:count].astype(np.int64).reshape(-1, 2)


def eye_pairs(
    graph: WaypointGraph, nodes: np.ndarray, eye_height: float = EYE_HEIGHT_M
) -> np.ndarray:
    """(P, 2, 3) eye points of node pairs: each waypoint (a floor point) raised by `eye_height`."""
    nodes = np.asarray(nodes, dtype=np.int64).reshape(-1, 2)
    if len(nodes) and (nodes.min() < 0 or nodes.max() >= graph.num_nodes):
        raise GraphError(f"node pairs refer to waypoints outside 0..{graph.num_nodes - 1}")
    return eye_point(graph.positions[nodes], eye_height)


@dataclass(frozen=True)
class PlaceDisagreement:
    """Pairs with an endpoint in one place, and how many of them the worlds disagree on."""

    place: str
    pairs: int
    disagree: int
    only_a: int
    only_b: int

    @property
    def share(self) -> float:
        return self.disagree / self.pairs if self.pairs else float("nan")


def disagreement_by_place(
    comparison: LosComparison, nodes: np.ndarray, graph: WaypointGraph
) -> list[PlaceDisagreement]:
    """Per nav place, the pairs with at least one endpoint there and their disagreements,
    most disagreements first (a pair between two places counts for both; '-' = no place)."""
    nodes = np.asarray(nodes, dtype=np.int64).reshape(-1, 2)
    if len(nodes) != comparison.num_pairs:
        raise GraphError(f"{len(nodes)} node pairs for {comparison.num_pairs} compared pairs")
    names = [*graph.place_names, "-"]
    place = np.where(graph.node_place < 0, len(names) - 1, graph.node_place)[nodes]  # (P, 2)
    only_a = comparison.visible_a & ~comparison.visible_b
    only_b = comparison.visible_b & ~comparison.visible_a
    rows = []
    for k, name in enumerate(names):
        touches = (place == k).any(axis=1)
        if touches.any():
            rows.append(
                PlaceDisagreement(
                    place=name,
                    pairs=int(touches.sum()),
                    disagree=int(np.sum(touches & ~comparison.agree)),
                    only_a=int(np.sum(touches & only_a)),
                    only_b=int(np.sum(touches & only_b)),
                )
            )
    return sorted(rows, key=lambda r: (-r.disagree, r.place))
