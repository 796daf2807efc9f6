"""Where the replayed players look: the data's view (awpy `viewX`), for the combat step.

The damage models decide hits from where the attacker looks (its yaw against the direction of
the victim). A replay follows the data's movement and so takes the data's view too, where the
data records one; without it an agent looks along its motion (the simulator's yaw), and
`decoy_cli.replay.missing` names the view as inferred.
"""

from __future__ import annotations

import numpy as np


class DataViews:
    """The players' recorded yaw at any simulator tick: between two data frames it turns the
    shorter way from one to the other in proportion to the time; where one of the two frames
    has no view, the other's; NaN where neither has (the agent's own yaw is used)."""

    def __init__(self, frame_ticks: np.ndarray, yaw: np.ndarray) -> None:
        self.frame_ticks = np.asarray(frame_ticks, dtype=np.int64)
        self.yaw = np.asarray(yaw, dtype=np.float64)  # (P, F) degrees, NaN: not recorded
        if self.yaw.ndim != 2 or self.yaw.shape[1] != len(self.frame_ticks):
            raise ValueError(f"yaw of shape {self.yaw.shape} for {len(self.frame_ticks)} frames")

    def __call__(self, tick: int) -> np.ndarray:
        ticks = self.frame_ticks
        after = int(np.clip(np.searchsorted(ticks, tick, side="left"), 0, len(ticks) - 1))
        before = max(after - 1, 0) if ticks[after] > tick else after
        start, end = self.yaw[:, before], self.yaw[:, after]
        span = ticks[after] - ticks[before]
        share = (tick - ticks[before]) / span if span > 0 else 0.0
        share = float(np.clip(share, 0.0, 1.0))
        turn = (end - start + 180.0) % 360.0 - 180.0
        between = (start + share * turn) % 360.0
        return np.where(
            np.isfinite(start) & np.isfinite(end), between, np.where(np.isfinite(start), start, end)
        )


def data_views(frame_ticks: np.ndarray, yaw: np.ndarray) -> DataViews | None:
    """The data's views, or None when the data records no view at all."""
    return DataViews(frame_ticks, yaw) if np.isfinite(np.asarray(yaw, float)).any() else None
