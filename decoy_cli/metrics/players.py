"""The fidelity of every player of a replayed round: the table `evaluate`, `replay` and the
benchmark share.

A `ReplayTrace` is what the metrics need from a replay, in plain arrays (the replay layer
builds it with `ReplayResult.trace()`), so this module knows nothing of the simulator. Frames
where the data lost the player (absent from the frame's player list; some rounds miss a player
for many seconds) are left out of both trajectories: the original has no position there, and
the replay's path across the gap is a shortest path, not something the player did.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pandas as pd

from decoy_cli.esta import Round
from decoy_cli.metrics.trajectory import trajectory_metrics

REPLAY_COLUMNS = (
    "targets",
    "late_share",
    "late_over_frame",
    "late_zigzag",
    "late_detour",
    "late_speed",
    "late_gap",
    "late_replay",
    "late_p95_s",
    "stuck",
    "recoveries",
    "relocations",
)
"""Timing and the mover's troubles, per player (from `ReplayTrace`)."""

PLAYER_METRIC_COLUMNS = ("player", "side", "died_original", "died_replay", "death", *REPLAY_COLUMNS)
"""The columns of `player_metrics` before the ten trajectory metrics and `reason`."""


@dataclass(frozen=True)
class ReplayTrace:
    """A replayed round as the metrics see it: P players by F data frames.

    `position` (F, P, 3) and `alive` (F, P) at the data's frame times; per player: whether the
    data shows a death (`died_original`), whether the replay removed the player at its data
    death time rather than by combat (`scripted_death`), the share of plan targets reached late
    and the 95th percentile lateness in seconds (NaN when none was reached), the targets reached
    and how many of them more than one data frame late, split by why (the interval that added
    most lateness in its stretch of late targets up to it, against the speed the replay may
    run there: `late_zigzag` asked more only by the lattice's zig-zag, `late_detour`
    only by a way round something, the straight line would do; `late_speed` more even
    straight; `late_gap` across a gap of the graph, relocated; `late_replay` nothing beyond the
    cap, the replay's own delay), stuck
    episodes, recoveries (teleports) and relocations.
    """

    position: np.ndarray
    alive: np.ndarray
    died_original: np.ndarray
    scripted_death: np.ndarray
    late_share: np.ndarray
    late_p95_s: np.ndarray
    targets: np.ndarray
    late_over_frame: np.ndarray
    late_zigzag: np.ndarray
    late_detour: np.ndarray
    late_speed: np.ndarray
    late_gap: np.ndarray
    late_replay: np.ndarray
    stuck: np.ndarray
    recoveries: np.ndarray
    relocations: np.ndarray


def player_metrics(round_: Round, trace: ReplayTrace, *, fastdtw: bool = False) -> pd.DataFrame:
    """One row per player: identity, fate in both worlds, timing, and all ten metrics.

    Columns: `PLAYER_METRIC_COLUMNS`, the ten `METRIC_NAMES` (and `paper_dtw_fastdtw` with
    `fastdtw`), and reason (why the metrics are NaN, else None). `death` is "scripted",
    "simulated" or "".
    """
    rows = []
    for p, player in enumerate(round_.players):
        metrics = trajectory_metrics(
            np.asarray(round_.position[p]),
            np.asarray(round_.alive[p]),
            trace.position[:, p],
            trace.alive[:, p] & round_.present[p],
            fastdtw=fastdtw,
        )
        # a player never alive on the graph (absent) never lived in the replay: not a death
        died_replay = bool(trace.alive[:, p].any() and not trace.alive[-1, p])
        death = "scripted" if trace.scripted_death[p] else ("simulated" if died_replay else "")
        rows.append(
            {
                "player": player.name,
                "side": player.side,
                "died_original": bool(trace.died_original[p]),
                "died_replay": died_replay,
                "death": death,
                "targets": int(trace.targets[p]),
                "late_share": float(trace.late_share[p]),
                "late_over_frame": int(trace.late_over_frame[p]),
                "late_zigzag": int(trace.late_zigzag[p]),
                "late_detour": int(trace.late_detour[p]),
                "late_speed": int(trace.late_speed[p]),
                "late_gap": int(trace.late_gap[p]),
                "late_replay": int(trace.late_replay[p]),
                "late_p95_s": float(trace.late_p95_s[p]),
                "stuck": int(trace.stuck[p]),
                "recoveries": int(trace.recoveries[p]),
                "relocations": int(trace.relocations[p]),
                **metrics.values,
                "reason": metrics.reason,
            }
        )
    return pd.DataFrame(rows)
