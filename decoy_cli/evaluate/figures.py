"""The evaluation's figures, drawn from the aggregated tables (never from the match files).

* `heatmaps.png` (the paper's Figure 5): where the players were and where the replay put them
  (share of alive samples per cell, smoothed), and the signed percentage difference
  100·(replay − original) / mean(replay, original) as filled contours; nav places labelled.
* `error_map.png`: where the replay is off: the mean distance between replay and player (the
  clock protocol's per-frame distance), by where the player was, kernel-smoothed; red lines
  enclose where a quarter or more of the players' samples have no waypoint on their floor.
* `hp_over_time.png`: mean ± std HP of the player-frames in each second, original and replay.
* `death_times.png`: death time in the replay against the data, for players who died in both.
* `outcomes.png` (the paper's Figure 6): the rounds' winners and end reasons, original and
  replay side by side.

matplotlib is imported inside the functions (headless Agg backend).
"""

from __future__ import annotations

from pathlib import Path
from types import ModuleType
from typing import TYPE_CHECKING

import numpy as np

from decoy_cli.csgo import HAMMER_TO_M
from decoy_cli.evaluate.heat import HeatGrid
from decoy_cli.evaluate.tables import END_OF_DATA, NOT_RECORDED, UNDECIDED, Accumulator, Tables
from decoy_cli.figures import draw_nav_areas, save_figure

if TYPE_CHECKING:
    from matplotlib.axes import Axes

    from decoy_cli.world.navmesh import NavMesh

FIGURES_DIR = "figures"
"""The figures' folder in an evaluation's output folder."""

FIGURES = {
    "heatmaps": "heatmaps.png",
    "error_map": "error_map.png",
    "hp_over_time": "hp_over_time.png",
    "death_times": "death_times.png",
    "outcomes": "outcomes.png",
}
"""Figure name -> file name in the figures folder."""

SMOOTH_M = 1.0
"""Standard deviation of the Gaussian that smooths the heatmaps (metres)."""

_ORIGINAL = "#1f77b4"
_REPLAY = "#d62728"


def _pyplot() -> ModuleType:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def draw_figures(folder: Path, acc: Accumulator, tables: Tables, nav: NavMesh) -> dict[str, Path]:
    """Draw every figure into `folder`; returns name -> path."""
    paths = {name: folder / file for name, file in FIGURES.items()}
    draw_heatmaps(paths["heatmaps"], acc, nav)
    draw_error_map(paths["error_map"], acc, nav)
    draw_hp_over_time(paths["hp_over_time"], tables)
    draw_death_times(paths["death_times"], tables)
    draw_outcomes(paths["outcomes"], tables)
    return paths


def _smooth(grid: HeatGrid, values: np.ndarray) -> np.ndarray:
    from scipy.ndimage import gaussian_filter

    return gaussian_filter(values.astype(np.float64), SMOOTH_M / grid.cell, mode="constant")


def smoothed_shares(grid: HeatGrid, counts: np.ndarray) -> np.ndarray:
    """Counts as shares of all samples, smoothed by a Gaussian of `SMOOTH_M`."""
    total = counts.sum()
    return _smooth(grid, counts / total if total else counts)


def smoothed_error(grid: HeatGrid, count: np.ndarray, total_mm: np.ndarray) -> np.ndarray:
    """Kernel-weighted mean error (m) per cell: smoothed sum over smoothed count; NaN where
    the smoothed count is below one sample."""
    weight = _smooth(grid, count)
    with np.errstate(invalid="ignore", divide="ignore"):
        mean = _smooth(grid, total_mm) / 1000 / weight
    return np.where(weight >= 1.0, mean, np.nan)


def percentage_difference(original: np.ndarray, replay: np.ndarray, floor: float) -> np.ndarray:
    """100·(replay − original) / mean of the two, in [−200, 200]; NaN where both < floor."""
    mean = (original + replay) / 2
    with np.errstate(invalid="ignore", divide="ignore"):
        diff = 100 * (replay - original) / mean
    return np.where(mean >= floor, diff, np.nan)


def draw_heatmaps(path: Path, acc: Accumulator, nav: NavMesh) -> None:
    """Original and replay heatmaps and their percentage difference (see the module doc)."""
    from matplotlib.colors import LogNorm

    plt = _pyplot()
    grid = acc.settings.grid
    original = smoothed_shares(grid, acc.heat_original)
    replay = smoothed_shares(grid, acc.heat_replay)
    fig, axes = plt.subplots(1, 3, figsize=(21, 8.8), layout="constrained")
    top = max(float(original.max()), float(replay.max()), 1e-12)
    norm = LogNorm(vmin=top * 1e-3, vmax=top)
    for ax, shares, title in (
        (axes[0], original, f"original ({int(acc.heat_original.sum()):,} samples)"),
        (axes[1], replay, f"replay ({int(acc.heat_replay.sum()):,} samples)"),
    ):
        draw_nav_areas(ax, nav)
        shown = np.ma.masked_less(shares, top * 1e-3)
        image = ax.imshow(
            shown, origin="lower", extent=grid.extent, cmap="magma_r", norm=norm, zorder=1
        )
        ax.set_title(title)
    fig.colorbar(
        image, ax=axes[:2], location="bottom", shrink=0.5, label="share of samples per cell"
    )
    ax = axes[2]
    draw_nav_areas(ax, nav)
    diff = percentage_difference(original, replay, top * 1e-3)
    x = grid.x0 + (np.arange(grid.nx) + 0.5) * grid.cell
    y = grid.y0 + (np.arange(grid.ny) + 0.5) * grid.cell
    if np.isfinite(diff).any():
        levels = np.linspace(-200, 200, 17)
        contours = ax.contourf(
            x, y, np.ma.masked_invalid(diff), levels=levels, cmap="RdBu_r", extend="neither"
        )
        fig.colorbar(
            contours,
            ax=ax,
            location="bottom",
            shrink=0.9,
            label="100·(replay − original) / mean of the two (red: replay there more)",
        )
    ax.set_title("percentage difference")
    for ax in axes:
        _label_places(ax, nav)
        ax.set_xlim(grid.extent[0], grid.extent[1])
        ax.set_ylim(grid.extent[2], grid.extent[3])
        ax.set_aspect("equal")
        ax.set_xlabel("x (m, east)")
    axes[0].set_ylabel("y (m, north)")
    save_figure(fig, path)


def draw_error_map(path: Path, acc: Accumulator, nav: NavMesh) -> None:
    """The replay's mean distance from the player, by where the player was."""
    plt = _pyplot()
    grid = acc.settings.grid
    error = smoothed_error(grid, acc.error_count, acc.error_mm)
    fig, ax = plt.subplots(figsize=(10, 10), layout="constrained")
    draw_nav_areas(ax, nav)
    if np.isfinite(error).any():
        top = max(float(np.nanpercentile(error, 99)), 0.5)
        image = ax.imshow(
            np.ma.masked_invalid(error),
            origin="lower",
            extent=grid.extent,
            cmap="viridis",
            vmin=0,
            vmax=top,
            zorder=1,
        )
        fig.colorbar(image, ax=ax, shrink=0.7, label="mean distance replay ↔ player (m)")
    off = _smooth(grid, acc.heat_off_graph)
    seen = _smooth(grid, acc.heat_original)
    with np.errstate(invalid="ignore", divide="ignore"):
        off_share = np.where(seen >= 1.0, off / seen, 0.0)
    if (off_share >= 0.25).any():
        x = grid.x0 + (np.arange(grid.nx) + 0.5) * grid.cell
        y = grid.y0 + (np.arange(grid.ny) + 0.5) * grid.cell
        ax.contour(x, y, off_share, levels=[0.25], colors="#ff2020", linewidths=1.0, zorder=4)
        ax.plot([], [], color="#ff2020", lw=1.0, label="≥ 25% of the samples off the graph")
        ax.legend(loc="lower right", fontsize=8)
    total = int(acc.error_count.sum())
    mean = acc.error_mm.sum() / 1000 / total if total else float("nan")
    ax.set_title(
        f"where the replay is off: distance from the player at each frame, by the player's "
        f"position ({total:,} samples, mean {mean:.2f} m)",
        fontsize=10,
    )
    _label_places(ax, nav)
    ax.set_xlim(grid.extent[0], grid.extent[1])
    ax.set_ylim(grid.extent[2], grid.extent[3])
    ax.set_aspect("equal")
    ax.set_xlabel("x (m, east)")
    ax.set_ylabel("y (m, north)")
    save_figure(fig, path)


def _label_places(ax: Axes, nav: NavMesh) -> None:
    """Each nav place's name at the area-weighted centre of its areas."""
    area = (nav.x_max - nav.x_min) * (nav.y_max - nav.y_min)
    cx = (nav.x_min + nav.x_max) / 2 * HAMMER_TO_M
    cy = (nav.y_min + nav.y_max) / 2 * HAMMER_TO_M
    for place in nav.places:
        mine = nav.place == place
        weight = area[mine]
        if weight.sum() <= 0:
            continue
        ax.text(
            float(np.average(cx[mine], weights=weight)),
            float(np.average(cy[mine], weights=weight)),
            place,
            fontsize=6.5,
            color="#333333",
            ha="center",
            va="center",
            zorder=5,
        )


def draw_hp_over_time(path: Path, tables: Tables) -> None:
    """Mean ± std HP per second of the round, original and replay."""
    plt = _pyplot()
    curve = tables.hp_curve
    fig, ax = plt.subplots(figsize=(10, 5))
    for prefix, colour, label in (
        ("original", _ORIGINAL, "original"),
        ("replay", _REPLAY, "replay"),
    ):
        mean = curve[f"{prefix}_mean"].to_numpy(np.float64)
        std = np.nan_to_num(curve[f"{prefix}_std"].to_numpy(np.float64))
        ax.plot(curve["t_s"], mean, color=colour, label=f"{label} mean")
        ax.fill_between(curve["t_s"], mean - std, mean + std, color=colour, alpha=0.18, lw=0)
    if not len(curve):
        ax.text(0.5, 0.5, "no player-frame with a known HP", ha="center", transform=ax.transAxes)
    ax.set_ylim(-5, 110)
    ax.set_xlabel("seconds since freeze-time end")
    ax.set_ylabel("HP (dead = 0)")
    ax.set_title("HP over time: mean ± std over player-frames")
    ax.legend(loc="lower left")
    save_figure(fig, path)


def draw_death_times(path: Path, tables: Tables) -> None:
    """Replay against original death time of the players who died in both."""
    plt = _pyplot()
    players = tables.players
    both = players[players["died_original"] & players["died_replay"]]
    fig, ax = plt.subplots(figsize=(6.5, 6.5))
    x = both["death_time_original_s"].to_numpy(np.float64)
    y = both["death_time_replay_s"].to_numpy(np.float64)
    sides = both["side"].to_numpy()
    for side, colour in (("T", "#d62728"), ("CT", "#1f77b4")):
        mine = sides == side
        if mine.any():
            ax.scatter(
                x[mine], y[mine], s=12, alpha=0.6, color=colour, label=f"{side} ({mine.sum()})"
            )
    top = float(max(np.max(x, initial=0), np.max(y, initial=0), 1.0)) * 1.05
    ax.plot([0, top], [0, top], color="grey", lw=0.8, ls="--", label="same time")
    counts = tables.deaths.counts
    scripted = int((both["death"] == "scripted").sum())
    ax.set_title(
        f"death time: {counts['died_both']} died in both ({scripted} scripted from the data), "
        f"{counts['died_only_original']} only in the data, "
        f"{counts['died_only_simulated']} only in the replay",
        fontsize=9,
    )
    ax.set_xlim(0, top)
    ax.set_ylim(0, top)
    ax.set_aspect("equal")
    ax.set_xlabel("original (s since freeze-time end)")
    ax.set_ylabel("replay (s)")
    ax.legend(loc="upper left")
    save_figure(fig, path)


def draw_outcomes(path: Path, tables: Tables) -> None:
    """Counts of winners and end reasons, original next to replay."""
    plt = _pyplot()
    rounds = tables.rounds
    fig, axes = plt.subplots(1, 2, figsize=(13, 5), gridspec_kw={"width_ratios": [1, 2]})
    pairs = (
        ("winner", NOT_RECORDED, UNDECIDED, axes[0]),
        ("reason", NOT_RECORDED, END_OF_DATA, axes[1]),
    )
    for column, missing_original, missing_replay, ax in pairs:
        original = rounds[f"{column}_original"].fillna(missing_original).astype(str)
        replay = rounds[f"{column}_replay"].fillna(missing_replay).astype(str)
        labels = sorted(set(original) | set(replay))
        position = np.arange(len(labels))
        counts_o = [int((original == label).sum()) for label in labels]
        counts_r = [int((replay == label).sum()) for label in labels]
        ax.bar(position - 0.2, counts_o, width=0.4, color=_ORIGINAL, label="original")
        ax.bar(position + 0.2, counts_r, width=0.4, color=_REPLAY, label="replay")
        ax.set_xticks(position, labels, rotation=20, ha="right")
        ax.set_ylabel("rounds")
        ax.set_title("winner" if column == "winner" else "end reason")
        ax.legend()
    fig.suptitle(f"final outcome distribution ({len(rounds)} rounds)")
    save_figure(fig, path)
