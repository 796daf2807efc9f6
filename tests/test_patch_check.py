"""Which learned patches stay (decoy_cli/waypoints/patch_check.py): on a hand-made world of two
rooms joined by a doorway and by a passage at the far end, a learned box that fills the doorway
sends real players the long way round, and a box players stand on gives them waypoints."""

from __future__ import annotations

from functools import cache

import numpy as np
import pytest
from worlds import box, floor, make_world, seeds_of, wall

from decoy_cli.csgo import HAMMER_TO_M
from decoy_cli.waypoints import patch_check
from decoy_cli.waypoints.build import build_graph
from decoy_cli.waypoints.graph import WaypointGraph
from decoy_cli.waypoints.patch_check import (
    LENGTHENED_EXTRA_M,
    LENGTHENED_RATIO,
    PatchVerdict,
    _deep_inside,
    check_patches,
)
from decoy_cli.world.patch_learning import PatchBox, Tracks

SIZE = (12.0, 8.0)
"""The floor (x, y extent, metres); a wall at x = 6 splits it into two rooms."""
DOOR = (1.05, 2.35)
"""The doorway in the wall (y from, to); the wall runs on up to y = 6.4, leaving a passage."""
PASSAGE_Y = 6.4
DOOR_BOX = (5.45, 1.05, 6.55, 2.35, 1.5)
"""A learned box filling the doorway (x0, y0, x1, y1, top): too high to jump onto."""
STAND = (8.65, 3.45, 10.45, 5.25, 0.9)
"""A learned box players stand on (x0, y0, x1, y1, top): a crouch-jump reaches its top."""
SEED = (3.0, 4.0, 0.0)


def rooms(*boxes: tuple[float, ...]):
    width, depth = SIZE
    parts = [
        floor(0.0, 0.0, width, depth),
        wall(0.0, 0.0, width, 0.0, 0.0, 3.0),
        wall(width, 0.0, width, depth, 0.0, 3.0),
        wall(width, depth, 0.0, depth, 0.0, 3.0),
        wall(0.0, depth, 0.0, 0.0, 0.0, 3.0),
        wall(6.0, 0.0, 6.0, DOOR[0], 0.0, 3.0),
        wall(6.0, DOOR[1], 6.0, PASSAGE_Y, 0.0, 3.0),
    ]
    parts += [box(x0, y0, x1, y1, 0.0, top) for x0, y0, x1, y1, top in boxes]
    return make_world(parts, "rooms", SEED)


@cache
def graphs() -> tuple[WaypointGraph, WaypointGraph]:
    bare, patched = rooms(), rooms(DOOR_BOX, STAND)
    return (
        build_graph(bare, seeds=seeds_of(bare))[0],
        build_graph(patched, seeds=seeds_of(patched))[0],
    )


def patch_box(corners: tuple[float, ...], patch: int) -> PatchBox:
    x0, y0, x1, y1, top = (v / HAMMER_TO_M for v in corners)
    return PatchBox(
        x0, y0, x1, y1, top, 0.0, patch, samples=40, matches=3, height_spread_u=1.0,
        above_floor_u=top, place="Floor",
    )  # fmt: skip


BOXES = [patch_box(DOOR_BOX, 0), patch_box(STAND, 1)]

THROUGH_THE_DOOR = [(3.5, 1.7, 0.0), (5.2, 1.7, 0.0), (6.8, 1.7, 0.0), (8.5, 1.7, 0.0)]
"""A walk from the west room to the east one through the doorway, a frame each 1.7 m."""
IN_THE_DOOR = [(4.4, 1.7, 0.0), (6.0, 1.7, 0.0), (7.6, 1.7, 0.0)]
"""The same walk with a frame in the doorway itself, where the door box stands."""
ON_THE_STAND = [(9.2, 4.0, 0.9), (9.9, 4.7, 0.9), (9.5, 4.3, 0.9)]
BESIDE_THE_STAND = [(8.2, 4.3, 0.0), (11.0, 4.3, 0.0)]
"""On the floor either side of the stand: near a waypoint on both graphs, so nothing gained."""


def tracks(*walks: tuple[int, list[tuple[float, float, float]]]) -> Tracks:
    """Tracks of one walk per (match, positions); each walk is one player's run of frames."""
    position = np.concatenate([np.array(points, dtype=float) for _, points in walks])
    match = np.concatenate([np.full(len(points), m) for m, points in walks])
    follows = np.concatenate([np.arange(len(points)) > 0 for _, points in walks])
    return Tracks(position=position, match=match, follows=follows)


def test_the_door_box_sends_paths_round_and_the_stand_gives_positions() -> None:
    bare, patched = graphs()
    walks = tracks((0, THROUGH_THE_DOOR), (1, ON_THE_STAND), (1, BESIDE_THE_STAND))
    check = check_patches(bare, patched, BOXES, walks)
    door, stand = check.verdicts
    assert (door.lengthened, door.lengthened_matches, door.gained) == (1, 1, 0)
    assert (stand.lengthened, stand.gained) == (0, len(ON_THE_STAND))
    assert check.lengthened_pairs == 1
    # the stand's positions have no bare waypoint; the walk beside the stand is not lengthened
    assert check.pairs == len(THROUGH_THE_DOOR) - 1 + len(BESIDE_THE_STAND) - 1


def test_a_box_that_lengthens_paths_in_two_matches_is_left_out() -> None:
    bare, patched = graphs()
    walks = tracks((0, THROUGH_THE_DOOR), (1, THROUGH_THE_DOOR), (2, ON_THE_STAND))
    check = check_patches(bare, patched, BOXES, walks)
    assert [v.kept for v in check.verdicts] == [False, True]
    kept = check.kept_boxes(BOXES)
    assert [b.patch for b in kept] == [1]
    assert (kept[0].paths_lengthened, kept[0].positions_gained) == (0, len(ON_THE_STAND))


def test_a_frame_where_the_box_now_stands_counts_against_it() -> None:
    """A player stood in the doorway: the patched graph has no waypoint there, so the pairs
    into and out of that frame are lengthened (the box took the way)."""
    bare, patched = graphs()
    check = check_patches(bare, patched, BOXES, tracks((0, IN_THE_DOOR), (1, IN_THE_DOOR)))
    door = check.verdicts[0]
    assert (door.lengthened, door.lengthened_matches) == (4, 2)
    assert not door.kept


def test_the_path_searches_give_the_same_costs_in_any_batch_size(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    bare, patched = graphs()
    walks = tracks((0, THROUGH_THE_DOOR), (1, THROUGH_THE_DOOR[::-1]), (2, IN_THE_DOOR))
    whole = check_patches(bare, patched, BOXES, walks)
    monkeypatch.setattr(patch_check, "_SOURCES_PER_SEARCH", 1)
    assert check_patches(bare, patched, BOXES, walks) == whole


def test_one_matchs_detour_leaves_the_box_in() -> None:
    bare, patched = graphs()
    walks = tracks((0, THROUGH_THE_DOOR), (0, THROUGH_THE_DOOR), (1, ON_THE_STAND))
    check = check_patches(bare, patched, BOXES, walks)
    assert check.verdicts[0].lengthened == 2 and [v.kept for v in check.verdicts] == [True, True]


def test_the_detour_is_the_long_way_round() -> None:
    bare, patched = graphs()
    a, b = np.array(THROUGH_THE_DOOR[1]), np.array(THROUGH_THE_DOOR[2])
    costs = []
    for graph in (bare, patched):
        (source, target), _ = graph.nearest(np.array([a, b]), max_distance=0.5)
        nodes = graph.shortest_path(int(source), int(target))
        costs.append(float(np.linalg.norm(np.diff(graph.positions[nodes], axis=0), axis=1).sum()))
    assert costs[0] < np.linalg.norm(b - a) + 1.0
    assert costs[1] > LENGTHENED_RATIO * costs[0] + LENGTHENED_EXTRA_M
    assert costs[1] > 2 * (PASSAGE_Y - DOOR[1])  # up to the passage and back down


@pytest.mark.parametrize(
    ("lengthened", "matches", "gained", "kept"),
    [(0, 0, 0, True), (3, 2, 3, True), (4, 2, 3, False), (9, 1, 0, True), (9, 3, 0, False)],
)
def test_the_verdict_weighs_paths_lengthened_against_positions_gained(
    lengthened: int, matches: int, gained: int, kept: bool
) -> None:
    assert PatchVerdict(0, lengthened, matches, gained).kept is kept


def test_no_tracks_keep_every_patch() -> None:
    bare, patched = graphs()
    empty = Tracks(np.zeros((0, 3)), np.zeros(0, np.int64), np.zeros(0, bool))
    check = check_patches(bare, patched, BOXES, empty)
    assert check.pairs == 0 and all(v.kept for v in check.verdicts)


def test_a_pair_the_patched_graph_joins_much_shorter_is_credited_to_the_patch_beside_it() -> None:
    """The graphs swapped: the door box is in the 'bare' graph and the 'patched' one goes
    through the doorway, so the walk is much shorter there, beside the door box."""
    bare, patched = graphs()
    walks = tracks((0, THROUGH_THE_DOOR), (1, THROUGH_THE_DOOR))
    check = check_patches(patched, bare, BOXES, walks)
    door, stand = check.verdicts
    assert (door.shortened, door.lengthened) == (2, 0)
    assert stand.shortened == 0 and check.lengthened_pairs == 0


def test_only_a_spot_deep_inside_a_box_is_filled_by_it() -> None:
    x0, y0, x1, y1, top = DOOR_BOX
    box_m = np.array([[x0, y0, x1, y1, top, 0.0]])  # the patches file's column order
    points = np.array(
        [
            [(x0 + x1) / 2, (y0 + y1) / 2, 0.0],  # in the middle of the doorway
            [x0 + 0.1, (y0 + y1) / 2, 0.0],  # at the box's edge: grown over the feet
            [(x0 + x1) / 2, (y0 + y1) / 2, top + 1.0],  # above it
        ]
    )
    assert _deep_inside(points, box_m, np.array([0])).tolist() == [True, False, False]
