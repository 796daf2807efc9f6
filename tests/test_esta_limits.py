"""The reader's size limit: a match file's JSON is read and decompressed in bounded steps, so a
huge or hostile file is one clear error instead of exhausted memory."""

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
