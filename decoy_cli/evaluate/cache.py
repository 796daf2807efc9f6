"""The run cache in the output folder: one msgpack file per round result and per file index.

Every file is written atomically (decoy_cli/files.write_atomic) as soon as its result arrives,
so an interrupted run keeps every finished round, and a rerun loads them instead of computing
them again. Keys come from decoy_cli/evaluate/settings.py (file content, round, options, code),
so a changed option or a new version never reuses a stale result. A cache file that cannot be
decoded (written by another format version, or damaged), or that holds another key's result,
counts as missing; so does a key that is not a SHA-256 in hex (a run's summary.json names its
rounds' keys: an edited one could name a path out of the cache).
"""

from __future__ import annotations

import re
from pathlib import Path
from typing import TypeVar

import msgspec
import numpy as np

from decoy_cli.errors import DecoyError
from decoy_cli.evaluate.job import FileIndex
from decoy_cli.evaluate.record import RoundRecord
from decoy_cli.files import write_atomic
from decoy_cli.reading import open_regular

CACHE_DIR = "cache"
_KEY = re.compile("[0-9a-f]{64}")
"""What every cache key is (decoy_cli/evaluate/settings.py: a SHA-256 in hex)."""

Stored = TypeVar("Stored", RoundRecord, FileIndex)
"""What the cache stores."""


def _native(value: object) -> object:
    """numpy scalars as Python values (msgpack knows only the Python types)."""
    if isinstance(value, np.generic):
        return value.item()
    raise NotImplementedError(f"cannot store a {type(value).__name__} in the cache")


_ENCODER = msgspec.msgpack.Encoder(enc_hook=_native)
_ROUND_DECODER = msgspec.msgpack.Decoder(RoundRecord)
_INDEX_DECODER = msgspec.msgpack.Decoder(FileIndex)


class RunCache:
    """Round records under `<out>/cache/rounds`, file indexes under `<out>/cache/index`."""

    def __init__(self, out: Path) -> None:
        self.rounds = out / CACHE_DIR / "rounds"
        self.index = out / CACHE_DIR / "index"

    def round_path(self, key: str) -> Path:
        return self.rounds / f"{key}.msgpack"

    def index_path(self, key: str) -> Path:
        return self.index / f"{key}.msgpack"

    def load_round(self, key: str) -> RoundRecord | None:
        """The cached record, or None when missing, unreadable or not the record of `key` (a
        file copied or renamed within the cache)."""
        if not _KEY.fullmatch(key):
            return None
        record = _load(self.round_path(key), _ROUND_DECODER)
        return record if record is not None and record.key == key else None

    def store_round(self, record: RoundRecord) -> None:
        """Write a record atomically; a full disk raises OutputError."""
        write_atomic(self.round_path(record.key), _ENCODER.encode(record))

    def load_index(self, key: str, file_sha: str) -> FileIndex | None:
        """The cached index of the file with content `file_sha`, or None when missing,
        unreadable or another file's."""
        if not _KEY.fullmatch(key):
            return None
        index = _load(self.index_path(key), _INDEX_DECODER)
        return index if index is not None and index.file_sha == file_sha else None

    def store_index(self, key: str, index: FileIndex) -> None:
        write_atomic(self.index_path(key), _ENCODER.encode(index))


def _load(path: Path, decoder: msgspec.msgpack.Decoder[Stored]) -> Stored | None:
    """The record in `path`; None when it is missing, not a regular file or unreadable."""
    try:
        with open_regular(path) as handle:
            return decoder.decode(handle.read())
    except (DecoyError, OSError, msgspec.DecodeError):
        return None
