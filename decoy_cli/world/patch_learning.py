"""Floor patches learned from where real players stand: the boxes a map's nav mesh lacks.

What: where real players stand, again and again and in several matches, at a steady height
well above the nav world's floor, there is something solid the nav mesh does not have (a box, a
ledge, a step). This module turns those places into solid boxes, written as rows of the patches
file the world already reads (`world_patches.csv`), each row with its evidence.

Method:

1. **Standing positions.** An alive position on the ground: awpy's `velocityZ` is 0 (the
   Source engine keeps no vertical velocity on the ground). Where a file has no `velocityZ`,
   the same player's height must stay within `STEADY_U` over consecutive frames spanning at
   least `STEADY_S`; a jump or a fall changes height faster than that (a CS:GO jump is in the
   air for about 0.7 s).
2. **Raised.** The first floor of the nav world below the position (a ray down from a step above
   the feet, so a floor fitted a few units too high still counts as under the player) lies more
   than a step (sv_stepsize, 18 u) below: the player stands on something the nav mesh lacks.
3. **Clusters.** Raised standing positions are binned in `CELL_U` columns and `LAYER_U` layers;
   touching bins form one surface. A surface becomes a patch when it has at least
   `MIN_SAMPLES` positions from at least `min_matches` matches (one match can be one player's
   habit, or a glitch) and is flat (`MAX_SPREAD_U`): a sloping surface is uneven ground that the
   nav mesh fits too low, which a box would turn into a cliff.
4. **Boxes.** Each column of a patch is solid from the floor under it up to the median standing
   height there, unless more players stood on the floor below inside that column than on top
   (a passage under a ledge, not a box); where some players stood below with room to stand, it
   is a slab `SLAB_U` thick (a walkway). Gaps between columns are closed, and the patch grows
   by one column all round where no one stood below: players' centres stay up to half a hull
   from a surface's edge, so the surface reaches past them. Columns of equal height are merged
   into rectangles (`decoy_cli/world/patch_boxes.py`).

These are candidates: `decoy build-waypoints --learn-patches` keeps those the learning matches'
real paths are better with (`decoy_cli/waypoints/patch_check.py`).

Positions are read in Hammer units here (the nav mesh's units); the world is in metres.
"""

from __future__ import annotations

import csv
import io
from collections.abc import Sequence
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np
from scipy import ndimage

from decoy_cli.csgo import HAMMER_TO_M, STEP_HEIGHT_M
from decoy_cli.errors import WorldError
from decoy_cli.esta.reader import Match, read_match
from decoy_cli.files import write_atomic
from decoy_cli.world.nav_data import PATCH_COLUMNS, NavMesh
from decoy_cli.world.patch_boxes import CELL_U, STEP_U, rectangles, surface_columns
from decoy_cli.world.physics import PhysicsWorld

STEADY_U = 1.0
"""Largest height change between consecutive frames of a standing player (Hammer units)."""

STEADY_S = 0.4
"""Shortest time a player's height must stay steady to count as standing (seconds)."""

LAYER_U = 16.0
"""Height of a clustering layer; surfaces in touching layers join (Hammer units)."""

MAX_HEIGHT_U = 256.0
"""Highest surface above the floor below that is learned (Hammer units)."""

MAX_SPREAD_U = 4.0
"""Largest height spread (10th to 90th percentile) of a learned surface: boxes and ledges are
flat (Hammer units)."""

MIN_SAMPLES = 10
"""Fewest standing positions a patch needs."""

MIN_MATCHES = 2
"""Fewest matches a patch needs: a surface seen in one match only is not learned."""

MIN_ON_FLOOR = 0.5
"""Least share of a file's standing positions that must find a nav floor below them within
`MAX_HEIGHT_U`; fewer means wrong units or another map."""

MIN_SPAN = 0.05
"""Least share of the nav mesh's width and depth a match's positions must span; less means
positions in the wrong units (metres read as Hammer units cover a few units of the map)."""

EVIDENCE_COLUMNS = (
    "patch",
    "samples",
    "matches",
    "height_spread_u",
    "above_floor_u",
    "place",
    "paths_lengthened",
    "positions_gained",
    "paths_shortened",
)


@dataclass(frozen=True)
class StandingPositions:
    """Standing positions of a set of matches, Hammer units, with the match each came from."""

    position: np.ndarray  # (N, 3)
    match: np.ndarray  # (N,) index into `files`
    files: tuple[Path, ...]


@dataclass(frozen=True)
class Tracks:
    """Every alive position of the same matches' players, metres, player by player in frame
    order: the real paths a learned patch must not lengthen (`waypoints/patch_check.py`)."""

    position: np.ndarray  # (N, 3)
    match: np.ndarray  # (N,) index into the files
    follows: np.ndarray  # (N,) bool: the same player's position one frame after position i - 1


@dataclass(frozen=True)
class PatchBox:
    """One solid box of a learned patch, Hammer units, with the evidence of its patch."""

    x_min: float
    y_min: float
    x_max: float
    y_max: float
    z_top: float
    z_bottom: float
    patch: int
    samples: int
    matches: int
    height_spread_u: float
    above_floor_u: float
    place: str
    paths_lengthened: int | None = None
    """Real consecutive-frame paths the patch lengthens (None: not checked)."""
    positions_gained: int | None = None
    """Real positions only the patch puts near a waypoint (None: not checked)."""
    paths_shortened: int | None = None
    """Real consecutive-frame paths the patch shortens (None: not checked)."""

    def with_check(self, lengthened: int, gained: int, shortened: int) -> PatchBox:
        """The same box with the counts of its patch's check as evidence."""
        return replace(
            self,
            paths_lengthened=lengthened,
            positions_gained=gained,
            paths_shortened=shortened,
        )

    @property
    def box(self) -> tuple[float, ...]:
        """The box as its patches-file row reads back (`PATCH_COLUMNS`, to 0.1 u), so a world
        built from learned boxes is the world built from their file."""
        return tuple(round(float(getattr(self, key)), 1) for key in PATCH_COLUMNS)

    def row(self) -> dict[str, object]:
        what = (
            f"learned: {self.samples} standing positions from {self.matches} matches, "
            f"{self.above_floor_u:.0f} u above the nav floor"
        )
        return {
            **dict(zip(PATCH_COLUMNS, self.box, strict=True)),
            "what": what,
            **{key: getattr(self, key) for key in EVIDENCE_COLUMNS},
        }


def read_positions(
    files: Sequence[Path], map_name: str, nav: NavMesh
) -> tuple[StandingPositions, Tracks]:
    """The standing positions of every round of `files` (see the module docstring) and every
    alive position as tracks; a WorldError naming the file for one of another map or with
    positions in the wrong units."""
    standing, tracks, owners, track_owners = [], [], [], []
    for index, file in enumerate(files):
        match = read_match(file)
        if match.map_name and match.map_name != map_name:
            raise WorldError(f"{file}: a {match.map_name} match, not {map_name}")
        position = _match_standing(match)
        _check_spread(file, position, nav)
        standing.append(position)
        owners.append(np.full(len(position), index, dtype=np.int64))
        track = _match_tracks(match)
        tracks.append(track)
        track_owners.append(np.full(len(track[0]), index, dtype=np.int64))
    if not standing:
        empty = np.zeros((0, 3))
        nothing = np.zeros(0, dtype=np.int64)
        return (
            StandingPositions(position=empty, match=nothing, files=tuple(files)),
            Tracks(position=empty, match=nothing, follows=np.zeros(0, dtype=bool)),
        )
    return (
        StandingPositions(
            position=np.concatenate(standing), match=np.concatenate(owners), files=tuple(files)
        ),
        Tracks(
            position=np.concatenate([t[0] for t in tracks]),
            match=np.concatenate(track_owners),
            follows=np.concatenate([t[1] for t in tracks]),
        ),
    )


def _match_standing(match: Match) -> np.ndarray:
    """Standing positions of one match, Hammer units."""
    found = []
    for round_ in match.rounds:
        z = round_.position[..., 2] / HAMMER_TO_M
        ok = round_.alive & np.isfinite(round_.position).all(axis=-1)
        vz = round_.vertical_speed
        steady = _steady(np.where(ok, z, np.nan), round_.frame_seconds)
        standing = np.where(np.isnan(vz), steady, vz == 0) & ok
        found.append(round_.position[standing] / HAMMER_TO_M)
    return np.concatenate(found) if found else np.zeros((0, 3))


def _match_tracks(match: Match) -> tuple[np.ndarray, np.ndarray]:
    """(alive positions in metres, player by player in frame order; whether each follows the
    previous one frame later) of one match."""
    positions, follows = [], []
    for round_ in match.rounds:
        ok = round_.alive & np.isfinite(round_.position).all(axis=-1)  # (P, F)
        after_ok = np.zeros_like(ok)
        after_ok[:, 1:] = ok[:, :-1]
        positions.append(round_.position[ok])
        follows.append(after_ok[ok])
    if not positions:
        return np.zeros((0, 3)), np.zeros(0, dtype=bool)
    return np.concatenate(positions), np.concatenate(follows)


def _steady(z: np.ndarray, seconds: np.ndarray) -> np.ndarray:
    """(P, F) True where the height stays within STEADY_U of the next frame's over runs lasting
    at least STEADY_S."""
    players, frames = z.shape
    out = np.zeros((players, frames), dtype=bool)
    if frames < 2:
        return out
    with np.errstate(invalid="ignore"):
        flat = np.abs(np.diff(z, axis=1)) <= STEADY_U  # (P, F-1): frame f and f+1 agree
    for p in range(players):
        labels, runs = ndimage.label(flat[p])
        for run in range(1, runs + 1):
            links = np.flatnonzero(labels == run)
            first, last = links[0], links[-1] + 1
            if seconds[last] - seconds[first] >= STEADY_S:
                out[p, first : last + 1] = True
    return out


def _check_spread(file: Path, position: np.ndarray, nav: NavMesh) -> None:
    if len(position) == 0:
        return
    span = position[:, :2].max(axis=0) - position[:, :2].min(axis=0)
    extent = np.array([nav.x_max.max() - nav.x_min.min(), nav.y_max.max() - nav.y_min.min()])
    if np.any(span < MIN_SPAN * extent):
        raise WorldError(
            f"{file}: its players span {span[0]:.0f} x {span[1]:.0f} u of a {extent[0]:.0f} x "
            f"{extent[1]:.0f} u map: positions in the wrong units?"
        )


def floor_below(physics: PhysicsWorld, position: np.ndarray) -> np.ndarray:
    """Height (Hammer units) of the first floor below each position, looked for from a step
    above the feet down to MAX_HEIGHT_U below them (NaN where none)."""
    start = position * HAMMER_TO_M + np.array([0.0, 0.0, STEP_HEIGHT_M])
    depth = (STEP_U + MAX_HEIGHT_U) * HAMMER_TO_M
    z, _ = physics.first_floor_below(start, depth)
    return z / HAMMER_TO_M


def learn_patches(
    standing: StandingPositions,
    physics: PhysicsWorld,
    nav: NavMesh,
    *,
    min_matches: int = MIN_MATCHES,
) -> list[PatchBox]:
    """The boxes of the patches learned from `standing` on the world of `physics` (the map's
    nav world without patches); a WorldError naming the file whose positions find no floor."""
    position = standing.position
    floor = floor_below(physics, position)
    _check_on_floor(standing, floor)
    with np.errstate(invalid="ignore"):
        above = position[:, 2] - floor
        raised = above > STEP_U
        grounded = above <= STEP_U
    cells = np.floor(position[:, :2] / CELL_U).astype(np.int64)
    surface = _surfaces(position[raised], cells[raised])
    return _boxes(
        standing,
        np.flatnonzero(raised),
        surface,
        floor,
        cells,
        _ground_counts(cells[grounded], position[grounded, 2]),
        nav,
        min_matches,
    )


def _check_on_floor(standing: StandingPositions, floor: np.ndarray) -> None:
    for index, file in enumerate(standing.files):
        mine = standing.match == index
        if mine.any() and np.mean(np.isfinite(floor[mine])) < MIN_ON_FLOOR:
            raise WorldError(
                f"{file}: most of its players stand on no floor of this map "
                "(another map, or positions in the wrong units?)"
            )


def _surfaces(position: np.ndarray, cells: np.ndarray) -> np.ndarray:
    """A surface label (0, 1, ...) for each raised position: bins touching in 3-D join."""
    if len(position) == 0:
        return np.zeros(0, dtype=np.int64)
    layer = np.floor(position[:, 2] / LAYER_U).astype(np.int64)
    index = np.column_stack([cells, layer])
    index -= index.min(axis=0)
    grid = np.zeros(index.max(axis=0) + 1, dtype=bool)
    grid[tuple(index.T)] = True
    labels, _ = ndimage.label(grid, structure=np.ones((3, 3, 3)))
    return labels[tuple(index.T)].astype(np.int64) - 1


def _ground_counts(cells: np.ndarray, z: np.ndarray) -> dict[tuple[int, int], np.ndarray]:
    """Heights of the standing positions on the floor, by column."""
    if len(cells) == 0:
        return {}
    order = np.lexsort((cells[:, 1], cells[:, 0]))
    keys, starts = np.unique(cells[order], axis=0, return_index=True)
    groups = np.split(z[order], starts[1:])
    return {(int(k[0]), int(k[1])): g for k, g in zip(keys, groups, strict=True)}


def _boxes(
    standing: StandingPositions,
    raised_rows: np.ndarray,
    surface: np.ndarray,
    floor: np.ndarray,
    cells: np.ndarray,
    ground: dict[tuple[int, int], np.ndarray],
    nav: NavMesh,
    min_matches: int,
) -> list[PatchBox]:
    boxes: list[PatchBox] = []
    patch = 0
    for label in range(int(surface.max()) + 1 if len(surface) else 0):
        rows = raised_rows[surface == label]
        matches = len(np.unique(standing.match[rows]))
        if len(rows) < MIN_SAMPLES or matches < min_matches:
            continue
        z = standing.position[rows, 2]
        if np.percentile(z, 90) - np.percentile(z, 10) > MAX_SPREAD_U:
            continue  # not flat: uneven ground the nav mesh fits too low, not a box
        columns = surface_columns(cells[rows], z, floor[rows], ground)
        if not columns:
            continue
        centre = standing.position[rows, :2].mean(axis=0)
        spread = float(np.percentile(z, 90) - np.percentile(z, 10))
        for corners in rectangles(columns):
            boxes.append(
                PatchBox(
                    *corners,
                    patch=patch,
                    samples=len(rows),
                    matches=matches,
                    height_spread_u=round(spread, 1),
                    above_floor_u=round(float(np.median(z - floor[rows])), 1),
                    place=_place(nav, centre),
                )
            )
        patch += 1
    return boxes


def _place(nav: NavMesh, xy: np.ndarray) -> str:
    """The nav place of the area nearest to a point (horizontally)."""
    dx = np.maximum(np.maximum(nav.x_min - xy[0], xy[0] - nav.x_max), 0)
    dy = np.maximum(np.maximum(nav.y_min - xy[1], xy[1] - nav.y_max), 0)
    return str(nav.place[int(np.argmin(np.hypot(dx, dy)))])


def patches_csv(boxes: Sequence[PatchBox]) -> str:
    """The text of a patches file holding `boxes` (the world reads PATCH_COLUMNS)."""
    out = io.StringIO()
    writer = csv.DictWriter(
        out, fieldnames=[*PATCH_COLUMNS, "what", *EVIDENCE_COLUMNS], lineterminator="\n"
    )
    writer.writeheader()
    for box in boxes:
        writer.writerow(box.row())
    return out.getvalue()


def write_patches(path: Path, boxes: Sequence[PatchBox]) -> Path:
    """Write a patches file whole or not at all."""
    return write_atomic(path, patches_csv(boxes).encode())
