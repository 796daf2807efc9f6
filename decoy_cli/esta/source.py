"""From an ESTA file on disk to its top-level metadata and its rounds, still undecoded.

xz is recognised by its magic bytes, not by the file name; anything else is read as plain JSON.
msgspec splits the document into top-level values left as raw JSON, so each round is decoded on
its own later and a bad round fails alone. Strict JSON has no NaN, but Python's `json` writes
`NaN` for a float nan: a document msgspec rejects is parsed again with `json` (which accepts
NaN), so that the reader can name the round, frame and player that hold the NaN.
"""

from __future__ import annotations

import json
import lzma
import os
from dataclasses import dataclass
from pathlib import Path
from typing import TypeAlias

import msgspec

from decoy_cli.errors import EstaError
from decoy_cli.esta.schema import Invalid, RoundHead, RoundState
from decoy_cli.files import JsonObject, JsonValue
from decoy_cli.reading import open_regular

XZ_MAGIC = b"\xfd7zXZ\x00"

_TOP_DECODER = msgspec.json.Decoder(dict[str, msgspec.Raw])
_LIST_DECODER = msgspec.json.Decoder(list[msgspec.Raw])
_ROUND_DECODER = msgspec.json.Decoder(RoundState)
_HEAD_DECODER = msgspec.json.Decoder(RoundHead)
_DECODE_ERRORS = (msgspec.MsgspecError, UnicodeDecodeError, RecursionError)
"""What decoding a raw value can raise: the first pass skips values without checking UTF-8."""

RoundSource: TypeAlias = "msgspec.Raw | JsonValue"
"""A `gameRounds` entry: msgspec.Raw (the fast path) or an already parsed object (NaN path)."""


@dataclass
class Document:
    """A match file split into metadata (decoded) and rounds (not yet decoded)."""

    top: JsonObject
    rounds: list[RoundSource]


MAX_MATCH_MB_DEFAULT = 512
"""Largest match file, in MB of JSON after decompression, that the reader takes: many times the
largest real ESTA file seen (the T-side files hold about 21 MB), and small enough that a
hostile file cannot exhaust memory. The environment variable `DECOY_MAX_MATCH_MB` overrides it."""


LENIENT_MAX_MB = 64
"""Largest document, in MB of JSON, read by the `json` fallback that accepts NaN and Infinity:
three times the largest real ESTA file seen; Python's objects take several times their JSON's
size, so a larger document must be strict JSON (decoded by msgspec, round by round)."""

MAX_ROUNDS = 200
"""Most rounds a match file may hold: regulation is 30 rounds and each overtime 6, so 200 is
beyond any real match (the files in ../shared/data hold at most 30). Bounds the memory of a
hostile file of empty rounds."""


def max_match_bytes() -> int:
    """The size limit of a match file's JSON, in bytes (`MAX_MATCH_MB_DEFAULT` or the
    environment's `DECOY_MAX_MATCH_MB`)."""
    text = os.environ.get("DECOY_MAX_MATCH_MB", "")
    try:
        megabytes = float(text) if text else float(MAX_MATCH_MB_DEFAULT)
    except ValueError:
        raise EstaError(f"DECOY_MAX_MATCH_MB must be a number of MB, not {text!r}") from None
    if not megabytes > 0:
        raise EstaError(f"DECOY_MAX_MATCH_MB must be positive, not {text!r}")
    return int(megabytes * 1e6)


def read_bytes(path: Path) -> bytes:
    """The file's JSON bytes, decompressed when the file is xz; at most `max_match_bytes()`,
    read and decompressed in bounded steps, so a huge or hostile file fails instead of filling
    memory."""
    limit = max_match_bytes()
    too_big = (
        f"{path}: larger than {limit / 1e6:g} MB of JSON (set DECOY_MAX_MATCH_MB to allow more)"
    )
    with open_regular(path, EstaError) as handle:  # a FIFO or a device is refused unopened
        try:
            data = handle.read(limit + 1)
        except OSError as error:
            raise EstaError(f"{path}: cannot read the file ({error.strerror})") from None
    if not data.startswith(XZ_MAGIC):
        if len(data) > limit:
            raise EstaError(too_big)
        return data
    parts: list[bytes] = []
    size = 0
    rest = data
    while rest:  # one xz stream after another (xz may concatenate them), within the limit
        decompressor = lzma.LZMADecompressor()
        try:
            part = decompressor.decompress(rest, max_length=limit + 1 - size)
        except (lzma.LZMAError, EOFError) as error:
            raise EstaError(f"{path}: corrupt or truncated xz data ({error})") from None
        size += len(part)
        if size > limit or (not decompressor.eof and not decompressor.needs_input):
            raise EstaError(too_big)
        if not decompressor.eof:
            raise EstaError(f"{path}: corrupt or truncated xz data (the stream ends early)")
        parts.append(part)
        rest = decompressor.unused_data.lstrip(b"\0")  # xz allows zero padding between streams
    return b"".join(parts)


def parse(path: Path, data: bytes) -> Document:
    """Split the JSON document into metadata and raw rounds; file-level problems raise."""
    try:
        parts = _TOP_DECODER.decode(data)
    except msgspec.ValidationError:
        raise EstaError(f"{path}: not an ESTA match file (the JSON is not an object)") from None
    except (msgspec.DecodeError, UnicodeDecodeError, RecursionError) as error:
        return _parse_lenient(path, data, error)
    if "gameRounds" not in parts:
        raise EstaError(f"{path}: not an ESTA match file (no gameRounds)")
    try:
        rounds = _LIST_DECODER.decode(parts.pop("gameRounds"))
    except msgspec.ValidationError:
        raise EstaError(f"{path}: not an ESTA match file (gameRounds is not a list)") from None
    try:
        top = {key: msgspec.json.decode(raw) for key, raw in parts.items()}
    except _DECODE_ERRORS as error:
        raise EstaError(f"{path}: unreadable top-level metadata ({_describe(error)})") from None
    return Document(top=top, rounds=_check_count(path, list(rounds)))


def _parse_lenient(path: Path, data: bytes, strict_error: Exception) -> Document:
    """Parse with Python's json, which accepts NaN and Infinity; still invalid: EstaError. Python
    objects take many times their JSON's size, so only documents up to `LENIENT_MAX_MB` take
    this path."""
    if len(data) > LENIENT_MAX_MB * 1_000_000:
        message = _lower_first(str(strict_error))
        raise EstaError(
            f"{path}: invalid JSON ({message}); a file over {LENIENT_MAX_MB} MB of JSON must be "
            "strict JSON (no NaN or Infinity)"
        )
    try:
        document = json.loads(data)
    except (ValueError, RecursionError):
        message = str(strict_error)
        message = _lower_first(message)
        raise EstaError(f"{path}: invalid JSON ({message})") from None
    if not isinstance(document, dict):
        raise EstaError(f"{path}: not an ESTA match file (the JSON is not an object)")
    if "gameRounds" not in document:
        raise EstaError(f"{path}: not an ESTA match file (no gameRounds)")
    rounds = document.pop("gameRounds")
    if not isinstance(rounds, list):
        raise EstaError(f"{path}: not an ESTA match file (gameRounds is not a list)")
    return Document(top=document, rounds=_check_count(path, rounds))


def _check_count(path: Path, rounds: list[RoundSource]) -> list[RoundSource]:
    if len(rounds) > MAX_ROUNDS:
        raise EstaError(
            f"{path}: {len(rounds):,} rounds in gameRounds (a match file holds at most "
            f"{MAX_ROUNDS})"
        )
    return rounds


def decode_round(source: RoundSource) -> RoundState:
    """Decode one round into typed structs; a wrong type raises Invalid with its JSON path."""
    try:
        if isinstance(source, msgspec.Raw):
            return _ROUND_DECODER.decode(source)
        return msgspec.convert(source, RoundState)
    except _DECODE_ERRORS as error:
        raise Invalid(_describe(error)) from None


def round_number_hint(source: RoundSource) -> float | None:
    """The round's `roundNum` alone, or None when even that cannot be decoded."""
    try:
        if isinstance(source, msgspec.Raw):
            return _HEAD_DECODER.decode(source).roundNum
        return msgspec.convert(source, RoundHead).roundNum
    except _DECODE_ERRORS:
        return None


def _describe(error: Exception) -> str:
    """msgspec's message with the JSON path made relative to the round."""
    message = str(error).replace(" - at `$.", " at `").replace(" - at `$", " at `")
    return _lower_first(message)


def _lower_first(message: str) -> str:
    """The message with its first word in lower case, unless it is an acronym ("JSON")."""
    if message[1:2].isupper():
        return message
    return message[:1].lower() + message[1:]
