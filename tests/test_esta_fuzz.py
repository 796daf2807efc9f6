"""Fuzzing the ESTA reader: a mutated fixture gives a valid Match or an EstaError, nothing else.

Hypothesis draws mutations of a copy of the fixture match (tests/esta_fixtures.py): delete keys
or list items, swap values for other types, inject nulls, NaN, infinities, huge numbers and
strings; then maybe damage the bytes (truncate, flip a byte) and compress with xz (maybe cut).
"""

from __future__ import annotations

import copy
import json
import lzma
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from esta_fixtures import encode, make_match
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from decoy_cli.csgo import HAMMER_TO_M
from decoy_cli.errors import EstaError
from decoy_cli.esta import MISSING, Match, Round, read_match
from decoy_cli.esta.frames import MAX_COORD_U
from decoy_cli.weapons import is_known

_BASE = encode(make_match())
_TABLES = ("damages", "kills", "bomb_events")
_DELETE = "<delete>"
_REPLACEMENTS: list[Any] = [
    _DELETE,
    None,
    float("nan"),
    float("inf"),
    -1.0e308,
    2**70,
    -1,
    0,
    1.5,
    12_345.0,
    True,
    "",
    "AK-47",
    "not a value",
    [],
    [None],
    {},
    {"x": 1},
]


def _paths(node: Any, prefix: tuple[Any, ...] = ()) -> Iterator[tuple[Any, ...]]:
    """Every path to a value inside the document."""
    if isinstance(node, dict):
        items = node.items()
    elif isinstance(node, list):
        items = enumerate(node)
    else:
        return
    for key, child in items:
        yield (*prefix, key)
        yield from _paths(child, (*prefix, key))


_PATHS = list(_paths(make_match()))


def _apply(document: Any, path: tuple[Any, ...], replacement: Any) -> None:
    """Replace or delete the value at `path`; a path an earlier deletion removed is skipped."""
    parent = document
    try:
        for key in path[:-1]:
            parent = parent[key]
        parent[path[-1]]
    except (KeyError, IndexError, TypeError):
        return
    if isinstance(replacement, str) and replacement == _DELETE:
        del parent[path[-1]]
    else:
        parent[path[-1]] = copy.deepcopy(replacement)


mutations = st.lists(st.tuples(st.sampled_from(_PATHS), st.sampled_from(_REPLACEMENTS)), max_size=4)
byte_damage = st.one_of(
    st.none(),
    st.tuples(st.just("truncate"), st.floats(0, 1), st.just(0)),
    st.tuples(st.just("flip"), st.floats(0, 1), st.integers(1, 255)),
)
compression = st.one_of(st.none(), st.just(1.0), st.floats(0, 1))
"""None: plain JSON; a fraction: xz, cut to that fraction of its length (1.0: whole)."""


def _damaged_file(
    changes: list[tuple[tuple[Any, ...], Any]],
    damage: tuple[str, float, int] | None,
    xz_fraction: float | None,
) -> bytes:
    document = json.loads(_BASE)
    for path, replacement in changes:
        _apply(document, path, replacement)
    data = encode(document)
    if damage is not None:
        kind, fraction, xor = damage
        at = min(int(fraction * len(data)), len(data) - 1)
        data = (
            data[:at]
            if kind == "truncate"
            else data[:at] + bytes([data[at] ^ xor]) + data[at + 1 :]
        )
    if xz_fraction is not None:
        data = lzma.compress(data)
        data = data[: max(1, int(xz_fraction * len(data)))]
    return data


@pytest.fixture(scope="module")
def fuzz_file(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return tmp_path_factory.mktemp("fuzz") / "match.json.xz"


@settings(max_examples=500, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(changes=mutations, damage=byte_damage, xz_fraction=compression)
def test_reader_returns_a_valid_match_or_raises_esta_error(
    fuzz_file: Path,
    changes: list[tuple[tuple[Any, ...], Any]],
    damage: tuple[str, float, int] | None,
    xz_fraction: float | None,
) -> None:
    data = _damaged_file(changes, damage, xz_fraction)
    fuzz_file.write_bytes(data)
    try:
        match = read_match(fuzz_file)
    except EstaError as error:
        _assert_one_line(error, fuzz_file)
        return
    _assert_valid_match(match)
    for num in match.round_numbers:
        try:
            match.round(num)
        except EstaError as error:
            _assert_one_line(error, fuzz_file)


def _assert_one_line(error: EstaError, path: Path) -> None:
    message = str(error)
    assert message.startswith(f"{path}: ") and "\n" not in message


def _assert_valid_match(match: Match) -> None:
    assert isinstance(match.match_id, str) and isinstance(match.map_name, str)
    assert isinstance(match.tick_rate, int) and match.tick_rate > 0
    numbers = [r.round_num for r in match.rounds]
    assert numbers == sorted(set(numbers)) and not set(numbers) & set(match.round_errors)
    for played in match.rounds:
        _assert_valid_round(played)


def _assert_valid_round(played: Round) -> None:
    p, f = played.num_players, played.num_frames
    for name in ("yaw", "hp", "armor", "helmet", "has_defuser", "weapon", "alive", "present"):
        assert getattr(played, name).shape == (p, f), name
    assert played.position.shape == (p, f, 3) and played.bomb_position.shape == (f, 3)
    assert played.frame_seconds.shape == played.bomb_planted.shape == played.bombsite.shape == (f,)
    assert played.frame_ticks.dtype == np.int64 and (np.diff(played.frame_ticks) >= 0).all()
    assert np.isfinite(played.frame_seconds).all()
    present = played.present
    assert np.isfinite(played.position[present]).all()
    assert np.isnan(played.position[~present]).all()
    assert (np.abs(played.position[present]) <= MAX_COORD_U * HAMMER_TO_M).all()
    bomb = played.bomb_position[~np.isnan(played.bomb_position)]
    assert (np.abs(bomb) <= MAX_COORD_U * HAMMER_TO_M).all()
    assert not (played.alive & ~present).any()
    assert (played.hp[~present] == MISSING).all() and (played.hp >= MISSING).all()
    assert all(is_known(str(w)) for w in np.unique(played.weapon))
    keys = [player.key for player in played.players]
    assert len(set(keys)) == len(keys) and all(keys)
    assert {player.side for player in played.players} <= {"T", "CT"}
    assert played.winning_side in (None, "T", "CT")
    for table in _TABLES:
        frame_index = getattr(played, table)["frame_index"].to_numpy()
        assert ((frame_index >= -1) & (frame_index < max(f, 0) + (f == 0))).all()
        if f == 0:
            assert (frame_index == -1).all()
