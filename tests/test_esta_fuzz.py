"""Fuzzing the ESTA reader: a mutated fixture gives a valid Match or an EstaError, nothing else.

Hypothesis draws mutations of a copy of the fixture match (tests/esta_mutations.py).
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import pytest
from esta_mutations import byte_damage, compression, damaged_file, mutations
from hypothesis import HealthCheck, given, settings

from decoy_cli.csgo import HAMMER_TO_M
from decoy_cli.errors import EstaError
from decoy_cli.esta import MISSING, Match, Round, read_match
from decoy_cli.esta.frames import MAX_COORD_U
from decoy_cli.weapons import is_known

_TABLES = ("damages", "kills", "bomb_events")


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
    data = damaged_file(changes, damage, xz_fraction)
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
