"""What a replay produces for people and for other tools: files and pictures.

* `write_replay`: the replay as open files in a folder: `replay.csv` (one row per data frame
  and player: time, position, yaw, HP, alive, and the original position beside it),
  `events.csv` (every simulator event), `players.csv` (the per-player table),
  `summary.json` (outcome, options, counts) and `trace.json` (the thinned paths and events
  `decoy view` draws: decoy_cli/replay/view_trace.py).
* `plot_paths`: original versus replayed paths over the map; `animate`: an optional GIF.
"""

from __future__ import annotations

import json
from pathlib import Path

import msgspec
import numpy as np
import pandas as pd

from decoy_cli.csgo import TICK_RATE
from decoy_cli.errors import OutputError
from decoy_cli.esta import Round
from decoy_cli.figures import draw_nav_areas, save_figure
from decoy_cli.files import json_text, write_atomic, write_csv
from decoy_cli.replay.replayer import ReplayResult
from decoy_cli.replay.view_trace import round_trace
from decoy_cli.world.navmesh import NavMesh

TRACE_FILE = "trace.json"


def write_replay(
    folder: str | Path,
    round_: Round,
    result: ReplayResult,
    players: pd.DataFrame,
    summary: dict[str, object],
) -> list[Path]:
    """Write the replay files into `folder` (each atomically); returns their paths."""
    folder = Path(folder)
    try:
        folder.mkdir(parents=True, exist_ok=True)
    except OSError as error:
        raise OutputError(f"cannot create {folder}: {error.strerror or error}") from None
    rec = result.recording
    n_frames, n_players = rec.alive.shape if rec.alive.ndim == 2 else (0, 0)
    frame = np.repeat(np.arange(n_frames), n_players)
    player = np.tile(np.arange(n_players), n_frames)
    original = np.asarray(round_.position)  # (P, F, 3)
    table = pd.DataFrame(
        {
            "frame": frame,
            "tick": rec.ticks[frame] if n_frames else np.zeros(0, np.int64),
            "seconds": np.asarray(round_.frame_seconds)[frame] if n_frames else np.zeros(0),
            "player": [result.plan.players[p].name for p in player],
            "side": [result.plan.players[p].side for p in player],
            "x": rec.position[frame, player, 0],
            "y": rec.position[frame, player, 1],
            "z": rec.position[frame, player, 2],
            "yaw": rec.yaw[frame, player],
            "hp": rec.hp[frame, player],
            "alive": rec.alive[frame, player],
            "x_original": original[player, frame, 0],
            "y_original": original[player, frame, 1],
            "z_original": original[player, frame, 2],
            "alive_original": np.asarray(round_.alive)[player, frame],
        }
    )
    events = pd.DataFrame(
        [
            {
                "tick": e.tick,
                "seconds": e.tick / TICK_RATE,
                "kind": e.kind,
                "agent": result.plan.players[e.agent].name if e.agent >= 0 else "",
                "other": result.plan.players[e.other].name if e.other >= 0 else "",
                "data": json.dumps(e.data, sort_keys=True, default=str),
            }
            for e in result.events
        ],
        columns=["tick", "seconds", "kind", "agent", "other", "data"],
    )
    written = [
        write_csv(folder / name, frame)
        for name, frame in (("replay.csv", table), ("events.csv", events), ("players.csv", players))
    ]
    written.append(write_atomic(folder / "summary.json", json_text(summary).encode()))
    trace = msgspec.json.encode(round_trace(round_, result))
    written.append(write_atomic(folder / TRACE_FILE, trace))
    return written


def plot_paths(
    path: str | Path, round_: Round, result: ReplayResult, nav: NavMesh, title: str = ""
) -> None:
    """Original (dashed) versus replayed (solid) path of every player over the map."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    rec = result.recording
    fig, ax = plt.subplots(figsize=(11, 11))
    draw_nav_areas(ax, nav)
    colours = plt.get_cmap("tab10")
    for p, player in enumerate(result.plan.players):
        colour = colours(p % 10)
        alive_o = np.asarray(round_.alive[p])
        original = np.asarray(round_.position[p])[alive_o]
        replay = rec.position[rec.alive[:, p], p]
        if len(original):
            ax.plot(original[:, 0], original[:, 1], "--", color=colour, lw=1.0, alpha=0.8)
        if len(replay):
            ax.plot(replay[:, 0], replay[:, 1], "-", color=colour, lw=1.6, label=player.name)
            ax.plot(*replay[0, :2], "o", color=colour, ms=5)
            ax.plot(*replay[-1, :2], "x" if not rec.alive[-1, p] else "s", color=colour, ms=7)
    ax.set_aspect("equal")
    ax.autoscale_view()
    ax.legend(loc="lower right", fontsize=8, title="solid: replay, dashed: original")
    ax.set_xlabel("x (m, east)")
    ax.set_ylabel("y (m, north)")
    ax.set_title(title)
    save_figure(fig, path)


def animate(
    path: str | Path, round_: Round, result: ReplayResult, nav: NavMesh, fps: int = 8
) -> None:
    """An animated GIF of the round: replayed agents (filled) and originals (rings) per frame."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.animation import FuncAnimation, PillowWriter

    rec = result.recording
    sides = np.array([p.side for p in result.plan.players])
    colour = np.where(sides == "T", "#d62728", "#1f77b4")
    fig, ax = plt.subplots(figsize=(7, 7))
    draw_nav_areas(ax, nav)
    ax.set_aspect("equal")
    ax.autoscale_view()
    replay_dots = ax.scatter([], [], s=30)
    original_dots = ax.scatter([], [], s=40, facecolors="none")
    label = ax.set_title("")
    original = np.asarray(round_.position)
    alive_o = np.asarray(round_.alive)

    def draw(f: int):
        shown = rec.alive[f]
        replay_dots.set_offsets(rec.position[f, shown, :2])
        replay_dots.set_color(colour[shown])
        here = alive_o[:, f] & np.isfinite(original[:, f, 0])
        original_dots.set_offsets(original[here, f, :2])
        original_dots.set_edgecolor(colour[here])
        label.set_text(f"{np.asarray(round_.frame_seconds)[f]:.1f} s")
        return replay_dots, original_dots, label

    anim = FuncAnimation(fig, draw, frames=len(rec.ticks), blit=False)
    path = Path(path)
    tmp = path.with_name(f".{path.name}.tmp.gif")
    try:
        anim.save(tmp, writer=PillowWriter(fps=fps))
        tmp.replace(path)
    except OSError as error:
        tmp.unlink(missing_ok=True)
        raise OutputError(f"cannot write {path}: {error.strerror or error}") from None
    finally:
        plt.close(fig)
