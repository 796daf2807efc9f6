"""The content hash of a match: one way for every command to tell two inputs apart or alike."""

from __future__ import annotations

import hashlib
from pathlib import Path

from decoy_cli.errors import EstaError
from decoy_cli.reading import open_regular


def content_sha256(path: Path) -> str:
    """SHA-256 of a file's bytes, or of a folder of tables (awpy 3's: each regular file's name
    and bytes, in name order); an unreadable one, or a file that is not a regular file (a FIFO
    would block the read forever), raises EstaError."""
    digest = hashlib.sha256()
    try:
        files = sorted(p for p in path.iterdir() if p.is_file()) if path.is_dir() else [path]
        for file in files:
            if path.is_dir():
                digest.update(file.name.encode() + b"\0")
            with open_regular(file, EstaError) as handle:
                for block in iter(lambda: handle.read(1 << 20), b""):
                    digest.update(block)
    except OSError as error:
        raise EstaError(f"{path}: cannot read it ({error.strerror or error})") from None
    return digest.hexdigest()
