"""The solid boxes of one learned floor patch: columns, closed and grown, merged into rectangles.

`decoy_cli/world/patch_learning.py` finds where players stand on something the nav mesh lacks;
this module turns one such surface into boxes. A column is `CELL_U` square; its top is the
median standing height in it, its bottom the floor below, or a slab's underside where players
stood below with room to stand. Hammer units throughout.
"""

from __future__ import annotations

import numpy as np
from scipy import ndimage

from decoy_cli.csgo import HAMMER_TO_M, PLAYER_HEIGHT_M, STEP_HEIGHT_M

Columns = dict[tuple[int, int], tuple[float, float]]
"""(top, bottom) of each column of a surface, keyed by its cell (x, y indices)."""

STEP_U = STEP_HEIGHT_M / HAMMER_TO_M
"""sv_stepsize: a ledge up to this height is walked up; a player higher than this above the
floor is not standing on that floor."""

PLAYER_HEIGHT_U = PLAYER_HEIGHT_M / HAMMER_TO_M
"""Standing hull height: under a surface higher than this above the floor a player walks."""

SLAB_U = 16.0
"""Thickness of a patch that a player could walk under (Hammer units)."""

CELL_U = 16.0
"""Side of a patch column: half the player hull's width (Hammer units)."""


def surface_columns(
    cells: np.ndarray, z: np.ndarray, floor: np.ndarray, ground: dict[tuple[int, int], np.ndarray]
) -> Columns:
    """(top, bottom) of each solid column of one surface, rounded to whole units."""
    columns = {}
    for key in {(int(i), int(j)) for i, j in cells}:
        mine = (cells[:, 0] == key[0]) & (cells[:, 1] == key[1])
        top = float(np.round(np.median(z[mine])))
        bottom = float(np.floor(np.min(floor[mine])))
        below = ground.get(key, np.zeros(0))
        under = int(np.sum((below < top - STEP_U) & (below > bottom - STEP_U)))
        if under >= mine.sum():
            continue  # more players stood under it than on it: a passage, not a box
        if under and top - bottom > PLAYER_HEIGHT_U + SLAB_U:
            bottom = top - SLAB_U  # players stood under it: a walkway, not a box
        columns[key] = (top, bottom)
    return _fill_gaps(columns, ground)


def _fill_gaps(
    columns: Columns,
    ground: dict[tuple[int, int], np.ndarray],
) -> Columns:
    """Columns no one happened to stand on, between columns of the surface (a morphological
    closing), take the nearest column's top and bottom unless players stood on the floor there."""
    if not columns:
        return columns
    keys = np.array(list(columns))
    origin = keys.min(axis=0) - 2
    mask = np.zeros(keys.max(axis=0) - origin + 3, dtype=bool)
    mask[tuple((keys - origin).T)] = True
    closed = ndimage.binary_fill_holes(ndimage.binary_closing(mask, np.ones((3, 3))) | mask)
    closed = ndimage.binary_dilation(closed, np.ones((3, 3)))
    _, nearest = ndimage.distance_transform_edt(~mask, return_indices=True)
    filled = dict(columns)
    for i, j in np.argwhere(closed & ~mask):
        key = (int(i + origin[0]), int(j + origin[1]))
        source = (int(nearest[0, i, j] + origin[0]), int(nearest[1, i, j] + origin[1]))
        top, bottom = columns[source]
        below = ground.get(key, np.zeros(0))
        if not np.any((below < top - STEP_U) & (below > bottom - STEP_U)):
            filled[key] = (top, bottom)
    return filled


def rectangles(
    columns: Columns,
) -> list[tuple[float, float, float, float, float, float]]:
    """Columns of equal top, and alike solid or slab, merged into rectangles (runs along x,
    then equal runs along y); a merged solid box reaches down to its lowest column's floor."""
    groups: dict[tuple[float, bool], list[tuple[int, int]]] = {}
    for (i, j), (top, bottom) in columns.items():
        groups.setdefault((top, bottom == top - SLAB_U), []).append((j, i))
    out = []
    for (top, _), cells in groups.items():
        runs: dict[tuple[int, int], list[int]] = {}  # (first i, last i) -> rows j
        cells.sort()
        for j in sorted({j for j, _ in cells}):
            xs = [i for jj, i in cells if jj == j]
            first = 0
            for k in range(1, len(xs) + 1):
                if k < len(xs) and xs[k] == xs[k - 1] + 1:
                    continue
                runs.setdefault((xs[first], xs[k - 1]), []).append(j)
                first = k
        for (i0, i1), rows in runs.items():
            first = 0
            for k in range(1, len(rows) + 1):
                if k < len(rows) and rows[k] == rows[k - 1] + 1:
                    continue
                j0, j1 = rows[first], rows[k - 1]
                bottom = min(
                    columns[(i, j)][1] for i in range(i0, i1 + 1) for j in range(j0, j1 + 1)
                )
                out.append(
                    (i0 * CELL_U, j0 * CELL_U, (i1 + 1) * CELL_U, (j1 + 1) * CELL_U, top, bottom)
                )
                first = k
    return sorted(out)
