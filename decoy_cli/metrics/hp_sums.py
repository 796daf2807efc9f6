"""HP of a replayed round against the data as exact integer sums (pooled, per data frame, per
time bin), so that pooled HP metrics do not depend on the order in which rounds finish.
"""

from __future__ import annotations

import msgspec
import numpy as np


class HpStats(msgspec.Struct, frozen=True, array_like=True):
    """Integer HP sums of one round over its player-frames with a known original HP.

    `pooled` = [n, Σo, Σs, Σo², Σs², Σo·s, Σ(o−s)²]; `frame_*` per data frame index (for the
    population-mean curves); `bin_*` per bin of the HP time grid starting at `bin_first`.
    """

    pooled: list[int]
    frame_count: list[int]
    frame_sum_original: list[int]
    frame_sum_replay: list[int]
    bin_first: int
    bin_count: list[int]
    bin_sum_original: list[int]
    bin_sum2_original: list[int]
    bin_sum_replay: list[int]
    bin_sum2_replay: list[int]


def hp_stats(
    original: np.ndarray,
    replay: np.ndarray,
    frame_index: np.ndarray,
    frame_seconds: np.ndarray,
    bin_s: float,
    bins: int,
) -> HpStats:
    """Integer HP sums of pooled player-frames (original, replay HP at frame `frame_index`)."""
    o = np.asarray(original, dtype=np.int64)
    s = np.asarray(replay, dtype=np.int64)
    frames = np.asarray(frame_index, dtype=np.int64)
    size = len(frame_seconds)
    pooled = [
        len(o),
        int(o.sum()),
        int(s.sum()),
        int((o * o).sum()),
        int((s * s).sum()),
        int((o * s).sum()),
        int(((o - s) ** 2).sum()),
    ]
    frame_bin = np.floor(np.asarray(frame_seconds, dtype=np.float64) / bin_s).astype(np.int64)
    b = frame_bin[frames] if len(frames) else np.zeros(0, np.int64)
    keep = (b >= 0) & (b < bins)
    b, bo, bs = b[keep], o[keep], s[keep]
    first = int(b.min()) if len(b) else 0
    length = int(b.max()) - first + 1 if len(b) else 0

    def per_bin(weights: np.ndarray | None) -> list[int]:
        return np.bincount(b - first, weights=weights, minlength=length).astype(np.int64).tolist()

    def per_frame(weights: np.ndarray | None) -> list[int]:
        return np.bincount(frames, weights=weights, minlength=size).astype(np.int64).tolist()

    return HpStats(
        pooled=pooled,
        frame_count=per_frame(None),
        frame_sum_original=per_frame(o),
        frame_sum_replay=per_frame(s),
        bin_first=first,
        bin_count=per_bin(None),
        bin_sum_original=per_bin(bo),
        bin_sum2_original=per_bin(bo * bo),
        bin_sum_replay=per_bin(bs),
        bin_sum2_replay=per_bin(bs * bs),
    )
