"""The reader's limits: a match file's JSON is read and decompressed in bounded steps, and the
rounds, frames and players it may hold are bounded, so a huge or hostile file is one clear error
instead of exhausted memory (benchmarks/faults/hostile_memory.py measures the memory)."""

from __future__ import annotations

import lzma
from pathlib import Path

import pytest
from esta_fixtures import encode, make_match, write_match

from decoy_cli.errors import EstaError
from decoy_cli.esta import read_match
from decoy_cli.esta.source import MAX_MATCH_MB_DEFAULT, max_match_bytes, read_bytes


def test_the_default_limit_and_its_override(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.delenv("DECOY_MAX_MATCH_MB", raising=False)
    assert max_match_bytes() == MAX_MATCH_MB_DEFAULT * 1_000_000
    monkeypatch.setenv("DECOY_MAX_MATCH_MB", "2.5")
    assert max_match_bytes() == 2_500_000
    for bad in ("lots", "0", "-1"):
        monkeypatch.setenv("DECOY_MAX_MATCH_MB", bad)
        with pytest.raises(EstaError, match="DECOY_MAX_MATCH_MB must be"):
            max_match_bytes()


@pytest.mark.parametrize("name", ["m.json", "m.json.xz"])
def test_a_file_over_the_limit_is_one_error(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, name: str
) -> None:
    file = write_match(tmp_path / name)
    size = len(encode(make_match()))
    monkeypatch.setenv("DECOY_MAX_MATCH_MB", str((size - 1) / 1e6))
    with pytest.raises(EstaError) as raised:
        read_match(file)
    assert str(raised.value) == (
        f"{file}: larger than {(size - 1) / 1e6:g} MB of JSON (set DECOY_MAX_MATCH_MB to allow "
        "more)"
    )
    monkeypatch.setenv("DECOY_MAX_MATCH_MB", str(size / 1e6))
    assert read_match(file).match_id == "fixture-0001"


def test_an_xz_bomb_stops_at_the_limit(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    bomb = tmp_path / "bomb.json.xz"
    bomb.write_bytes(lzma.compress(b"[" + b"0," * 5_000_000 + b"0]"))  # 10 MB of JSON
    assert bomb.stat().st_size < 10_000
    monkeypatch.setenv("DECOY_MAX_MATCH_MB", "1")
    with pytest.raises(EstaError, match="larger than 1 MB of JSON"):
        read_bytes(bomb)


def test_concatenated_and_truncated_xz_streams(tmp_path: Path) -> None:
    text = encode(make_match())
    half = len(text) // 2
    joined = tmp_path / "joined.json.xz"
    joined.write_bytes(lzma.compress(text[:half]) + lzma.compress(text[half:]))
    assert read_bytes(joined) == text
    cut = tmp_path / "cut.json.xz"
    cut.write_bytes(lzma.compress(text)[:-20])
    with pytest.raises(EstaError, match="corrupt or truncated xz data"):
        read_bytes(cut)


def test_a_malformed_file_keeps_the_acronym(tmp_path: Path) -> None:
    file = tmp_path / "mal.json"
    file.write_text('{"gameRounds": [}')
    with pytest.raises(EstaError) as raised:
        read_match(file)
    assert str(raised.value).startswith(f"{file}: invalid JSON (JSON is malformed: ")


def test_too_many_rounds_is_a_file_error(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    from decoy_cli.esta import source

    monkeypatch.setattr(source, "MAX_ROUNDS", 2)
    file = write_match(tmp_path / "m.json", make_match())
    with pytest.raises(EstaError) as raised:
        read_match(file)
    assert str(raised.value) == f"{file}: 3 rounds in gameRounds (a match file holds at most 2)"


@pytest.mark.parametrize(
    ("limit", "value", "expected"),
    [
        ("MAX_FRAMES", 3, "round 1: 4 frames (a round holds at most 3)"),
        ("MAX_PLAYERS", 8, "round 1: 9 distinct players in the frames (a server has at most 8)"),
    ],
)
def test_a_round_over_a_limit_is_that_round_failure(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, limit: str, value: int, expected: str
) -> None:
    from decoy_cli.esta import frames

    monkeypatch.setattr(frames, limit, value)
    file = write_match(tmp_path / "m.json", make_match())
    match = read_match(file)
    assert str(match.round_errors[1]) == f"{file}: {expected}"
    assert [r.round_num for r in match.rounds] == [3]  # round 2 is over the limit too


def test_too_many_player_frames_is_a_file_error(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    from decoy_cli.esta import reader

    monkeypatch.setattr(reader, "MAX_MATCH_PLAYER_FRAMES", 40)  # round 1: 9 x 4 = 36
    file = write_match(tmp_path / "m.json", make_match())
    with pytest.raises(EstaError) as raised:
        read_match(file)
    assert str(raised.value).startswith(f"{file}: more than 40 player-frames by round 2 ")


def test_only_small_documents_take_the_lenient_path(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """A NaN (as awpy may write) is read by the json fallback, but only up to its size limit."""
    from decoy_cli.esta import source

    text = encode(make_match()).replace(b'"bombPlantTick": null', b'"bombPlantTick": NaN', 1)
    assert b"NaN" in text
    file = tmp_path / "nan.json"
    file.write_bytes(text)
    assert read_match(file).match_id == "fixture-0001"
    monkeypatch.setattr(source, "LENIENT_MAX_MB", 0)
    with pytest.raises(EstaError, match="must be strict JSON"):
        read_match(file)
