"""The paper's DTW as the paper computed it: FastDTW (Salvador and Chan) with the `fastdtw` package.

The DECOY paper cites FastDTW and its evaluation imported `fastdtw`: `fastdtw(A, B, radius=1,
dist=euclidean)` with scipy's Euclidean point cost, on the resampled trajectories of the paper
protocol. `paper_dtw_fastdtw` is that call's distance divided by the length of the warping path
it returns, the normalisation of the exact `paper_dtw` (docs/metrics.md).

FastDTW is an approximation: it searches only a band around the path projected from a coarser
resolution, so its total cost is never below the exact DTW's minimum total cost (`dtw`; up to
the rounding of sums added in another order, `FASTDTW_RTOL`). The
per-step mean can still come out below `paper_dtw` when FastDTW's path is longer than the exact
one; the evaluation counts how often. The package is pure Python here (its C extension does not
build on current Pythons), which makes it far slower than the exact kernel: `decoy evaluate`
computes it only when asked (`--fastdtw`) or for the paper's own Table 2 setting.
"""

from __future__ import annotations

import numpy as np

RADIUS = 1
"""FastDTW's search radius; the package's default, as the paper's code called it."""

FASTDTW_RTOL = 1e-9
"""Relative difference below which FastDTW and the exact DTW count as equal: scipy's Euclidean
distance and the exact kernel add a point's squared coordinates in different orders."""


def fastdtw_mean(a: np.ndarray, b: np.ndarray) -> float:
    """FastDTW total cost of two curves over the length of its warping path (module doc)."""
    from fastdtw import fastdtw
    from scipy.spatial.distance import euclidean

    total, path = fastdtw(a, b, radius=RADIUS, dist=euclidean)
    return float(total) / len(path)
