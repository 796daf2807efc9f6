"""Line of sight compared between two worlds of the same map, for the same pairs of eye points.

Which world the simulator uses decides who can see (and shoot) whom. The built-in nav world is
an approximation (nav holes become walls; windows, low cover and door gaps vanish); a user's
brush mesh has its own gaps (missing props, no clip brushes, displacement mounds). This module
measures how much the two disagree:

* `compare_line_of_sight` ray-tests every pair in both worlds (one pybullet client per world,
  batched rays) and returns per-pair visibility, the agreement and the confusion counts;
* `check_placement` finds points that do not stand properly in a world (geometry inside the
  body, or no floor under the feet), so pairs whose endpoints are misplaced can be set apart;
* `plot_los_comparison` draws where the worlds disagree.

Which pairs to compare (waypoints of a graph, lifted to eye height) and the disagreement by nav
place are chosen over a waypoint graph, a layer above the world: decoy_cli/waypoints/los_pairs.py.
"""

from __future__ import annotations

from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from decoy_cli.csgo import PLAYER_HEIGHT_M, STEP_HEIGHT_M
from decoy_cli.errors import WorldError
from decoy_cli.figures import draw_nav_areas, save_figure
from decoy_cli.world.navmesh import NavMesh
from decoy_cli.world.physics import PhysicsWorld
from decoy_cli.world.world import World

CONFUSION_KEYS = ("both", "only_a", "only_b", "neither")
"""Confusion cells: both worlds see, only world A sees, only world B sees, neither sees."""


@dataclass(frozen=True)
class LosComparison:
    """Visibility of the same point pairs in world A and world B."""

    pairs_a: np.ndarray  # (P, 2, 3) eye points tested in world A, metres
    pairs_b: np.ndarray  # (P, 2, 3) eye points tested in world B (often the same)
    visible_a: np.ndarray  # (P,) bool
    visible_b: np.ndarray  # (P,) bool
    name_a: str
    name_b: str

    @property
    def num_pairs(self) -> int:
        return len(self.visible_a)

    @property
    def agree(self) -> np.ndarray:
        """(P,) True where both worlds give the same answer."""
        return self.visible_a == self.visible_b

    @property
    def agreement(self) -> float:
        """Share of pairs on which the worlds agree (NaN for no pairs)."""
        return float(np.mean(self.agree)) if self.num_pairs else float("nan")

    @property
    def confusion(self) -> dict[str, int]:
        """Pair counts: both see, only A sees, only B sees, neither sees."""
        a, b = self.visible_a, self.visible_b
        counts = (a & b, a & ~b, ~a & b, ~a & ~b)
        return {key: int(np.sum(c)) for key, c in zip(CONFUSION_KEYS, counts, strict=True)}

    def subset(self, mask: np.ndarray) -> LosComparison:
        """The comparison restricted to the pairs where `mask` is True."""
        mask = np.asarray(mask, dtype=bool)
        if mask.shape != (self.num_pairs,):
            raise WorldError(f"mask of shape {mask.shape} for {self.num_pairs} pairs")
        return LosComparison(
            self.pairs_a[mask],
            self.pairs_b[mask],
            self.visible_a[mask],
            self.visible_b[mask],
            self.name_a,
            self.name_b,
        )

    def summary(self) -> dict[str, object]:
        """Pairs, agreement and confusion counts as plain JSON-ready values."""
        return {
            "pairs": self.num_pairs,
            "agreement": self.agreement,
            "visible_a": float(np.mean(self.visible_a)) if self.num_pairs else float("nan"),
            "visible_b": float(np.mean(self.visible_b)) if self.num_pairs else float("nan"),
            **self.confusion,
        }


@contextmanager
def _physics(world: World | PhysicsWorld) -> Iterator[PhysicsWorld]:
    """Borrow an open physics world, or load a `World` for the duration of the block."""
    if isinstance(world, PhysicsWorld):
        yield world
    else:
        with PhysicsWorld(world) as physics:
            yield physics


def _name(world: World | PhysicsWorld) -> str:
    return world.world.name if isinstance(world, PhysicsWorld) else world.name


def _check_pairs(pairs: np.ndarray, what: str) -> np.ndarray:
    pairs = np.asarray(pairs, dtype=np.float64)
    if pairs.ndim != 3 or pairs.shape[1:] != (2, 3):
        raise WorldError(f"{what} must have shape (P, 2, 3), got {pairs.shape}")
    if not np.all(np.isfinite(pairs)):
        raise WorldError(f"{what} hold a NaN or infinite coordinate")
    return pairs


def compare_line_of_sight(
    world_a: World | PhysicsWorld,
    world_b: World | PhysicsWorld,
    pairs_a: np.ndarray,
    pairs_b: np.ndarray | None = None,
) -> LosComparison:
    """Ray-test point pairs ((P, 2, 3) metres) in two worlds; `pairs_b` defaults to `pairs_a`.

    A pair is visible in a world when the segment between its points meets no triangle.
    """
    pairs_a = _check_pairs(pairs_a, "pairs_a")
    pairs_b = pairs_a if pairs_b is None else _check_pairs(pairs_b, "pairs_b")
    if len(pairs_b) != len(pairs_a):
        raise WorldError(f"pairs_b has {len(pairs_b)} pairs, pairs_a has {len(pairs_a)}")
    with _physics(world_a) as physics:
        visible_a = physics.line_of_sight(pairs_a[:, 0], pairs_a[:, 1])
    with _physics(world_b) as physics:
        visible_b = physics.line_of_sight(pairs_b[:, 0], pairs_b[:, 1])
    return LosComparison(pairs_a, pairs_b, visible_a, visible_b, _name(world_a), _name(world_b))


def sideways(pairs: np.ndarray, distance: float) -> np.ndarray:
    """The pairs moved horizontally by `distance` metres, perpendicular to each pair's line
    (to the left looking from the first point to the second; negative: to the right).

    A pair whose answer changes when moved by a player's half width grazes an edge: its
    visibility depends on exactly where walls and corners stand.
    """
    pairs = _check_pairs(pairs, "pairs")
    delta = pairs[:, 1, :2] - pairs[:, 0, :2]
    length = np.linalg.norm(delta, axis=1, keepdims=True)
    left = np.divide(
        np.column_stack([-delta[:, 1], delta[:, 0]]),
        length,
        out=np.zeros_like(delta),
        where=length > 0,
    )
    return pairs + np.concatenate([left * distance, np.zeros((len(pairs), 1))], axis=1)[:, None]


# ---- placement --------------------------------------------------------------------------------


@dataclass(frozen=True)
class Placement:
    """How points (feet on a floor) stand in a world."""

    buried: np.ndarray  # (M,) something of the world between knee and head height above the feet
    floating: np.ndarray  # (M,) no floor within the tolerance below the feet

    @property
    def misplaced(self) -> np.ndarray:
        """(M,) buried or floating: eye rays from such a point do not mean what they should."""
        return self.buried | self.floating


def check_placement(
    world: World | PhysicsWorld,
    feet: np.ndarray,
    floor_tolerance: float = 0.5,
    knee: float = STEP_HEIGHT_M,
    head: float = PLAYER_HEIGHT_M,
) -> Placement:
    """Check feet positions ((M, 3) metres, e.g. waypoints of another world's graph) in a world.

    Buried: a ray up from knee height (the step height: a floor that much higher is still
    walked onto) to head height hits something, such as a sand mound over the feet. Floating:
    a ray down from knee height finds no surface within `floor_tolerance` below the feet, such
    as a waypoint on a box the world does not have.
    """
    feet = np.asarray(feet, dtype=np.float64).reshape(-1, 3)
    if not np.all(np.isfinite(feet)):
        raise WorldError("feet positions hold a NaN or infinite coordinate")
    up = np.array([0.0, 0.0, 1.0])
    with _physics(world) as physics:
        buried = ~physics.line_of_sight(feet + knee * up, feet + head * up)
        floor_z, _ = physics.first_floor_below(feet + knee * up, knee + floor_tolerance)
    return Placement(buried=buried, floating=np.isnan(floor_z))


def plot_los_comparison(
    comparison: LosComparison,
    path: str | Path,
    nav: NavMesh | None = None,
    title: str = "",
    dpi: int = 130,
) -> None:
    """Write a top-down PNG: one panel per disagreement kind (only A sees, only B sees), each
    with the disagreeing pairs' segments (faint) and midpoints over the map's nav areas."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.collections import LineCollection

    panels = (
        (comparison.visible_a & ~comparison.visible_b, f"only {comparison.name_a} sees", "#1f77b4"),
        (comparison.visible_b & ~comparison.visible_a, f"only {comparison.name_b} sees", "#d62728"),
    )
    fig, axes = plt.subplots(1, 2, figsize=(20, 10), sharex=True, sharey=True)
    for ax, (mask, label, colour) in zip(axes, panels, strict=True):
        if nav is not None:
            draw_nav_areas(ax, nav, edgecolor="none")
        segments = comparison.pairs_a[mask][:, :, :2]
        ax.add_collection(LineCollection(segments, colors=colour, lw=0.5, alpha=0.25))
        middle = segments.mean(axis=1)
        ax.scatter(middle[:, 0], middle[:, 1], s=3, c=colour, lw=0)
        ax.set_title(f"{label}: {int(mask.sum()):,} of {comparison.num_pairs:,} pairs")
        ax.set_aspect("equal")
        ax.autoscale_view()
        ax.set_xlabel("x (m, east)")
    axes[0].set_ylabel("y (m, north)")
    confusion = comparison.confusion
    fig.suptitle(
        title
        or f"line of sight, {comparison.name_a} vs {comparison.name_b}: "
        f"agreement {comparison.agreement:.1%} (both {confusion['both']:,}, "
        f"neither {confusion['neither']:,})"
    )
    save_figure(fig, path, dpi)
