"""The DECOY paper's published DIP and DOG checkpoints, fetched from its public repository.

`decoy models download-decoy` fetches the four files at a fixed commit of HATS-ICT/decoy (MIT)
from `PAPER_BASE_URL`, checks each against the SHA-256 and size recorded here, and imports them
(`decoy_cli.modeling.paper_import.import_paper`) into a model folder for `--models`. A file that
arrives short, or with another checksum, is refused before anything is imported; the files are
written under temporary names and renamed only when verified.
"""

from __future__ import annotations

import contextlib
import hashlib
import os
import tempfile
from dataclasses import dataclass
from pathlib import Path

from decoy_cli.errors import DownloadError, OutputError
from decoy_cli.esta.download import open_url, stream_body

PAPER_REPOSITORY = "HATS-ICT/decoy"
PAPER_COMMIT = "6f93b8efe5a778384ccd284c31b2141b6b0ce5da"
PAPER_BASE_URL = f"https://raw.githubusercontent.com/{PAPER_REPOSITORY}/{PAPER_COMMIT}"


@dataclass(frozen=True)
class PaperFile:
    """One published file: where it is in the repository, its SHA-256 and size in bytes."""

    path: str
    sha256: str
    size: int


PAPER_FILES = {
    "dip_best_model.pth": PaperFile(
        "models/train-di_20250328-183510_y5vpxd/checkpoints/best_model.pth",
        "6b58f2cdb52ae32301a32551f725743cdf41d4c068eee41e5e375909b2ec093f",
        245_218,
    ),
    "dip_args.json": PaperFile(
        "models/train-di_20250328-183510_y5vpxd/args.json",
        "738401e91cdb3f429d3ea354631ebc5e47a7bb5f41c58b9db9d62141a078ecf4",
        350,
    ),
    "dog_best_model.pth": PaperFile(
        "models/train-vae_20250321-040316_upf4hz/checkpoints/best_model.pth",
        "0bcf5df3e083d3a82e0104dae8bb385bc438f24adaba282409a385ab6aa6ea03",
        1_863_170,
    ),
    "dog_args.json": PaperFile(
        "models/train-vae_20250321-040316_upf4hz/args.json",
        "76d0b1b0254746e59a183f3b3568a345bf43d2c27413efd191b37a8a3c1a501b",
        398,
    ),
}
"""The files at `PAPER_COMMIT`, by the names `import_paper` reads."""


def download_paper_files(
    dest: Path, base_url: str = PAPER_BASE_URL, timeout: float = 60.0
) -> list[Path]:
    """Fetch and verify every file of `PAPER_FILES` into `dest` (module doc); files already
    there with the right checksum are kept. One DownloadError or OutputError line on failure."""
    dest = Path(dest)
    created = [p for p in (dest.parent, dest) if not p.exists()]
    try:
        dest.mkdir(parents=True, exist_ok=True)
    except OSError as error:
        raise OutputError(f"cannot write to {dest}: {error.strerror or error}") from None
    try:
        return _download_all(dest, base_url, timeout)
    except BaseException:
        for folder in reversed(created):  # leave no empty folders behind a failed download
            with contextlib.suppress(OSError):
                folder.rmdir()
        raise


def _download_all(dest: Path, base_url: str, timeout: float) -> list[Path]:
    written = []
    for name, expected in PAPER_FILES.items():
        target = dest / name
        if target.is_file() and _sha256(target) == expected.sha256:
            written.append(target)
            continue
        url = f"{base_url.rstrip('/')}/{expected.path}"
        try:
            fd, temporary = tempfile.mkstemp(prefix=f".{name}.", suffix=".part", dir=dest)
        except OSError as error:
            raise OutputError(f"cannot write to {dest}: {error.strerror or error}") from None
        part = Path(temporary)
        try:
            with os.fdopen(fd, "wb") as out:
                response = open_url(url, name, timeout)
                if response is None:
                    raise DownloadError(f"{name}: not found (HTTP 404) at {url}")
                with response:
                    digest, _ = stream_body(response, url, name, out, timeout, None)
            size = part.stat().st_size
            if size != expected.size or digest != expected.sha256:
                raise DownloadError(
                    f"{name}: {url} gave {size:,} bytes with SHA-256 {digest[:12]}…, expected "
                    f"{expected.size:,} bytes with {expected.sha256[:12]}…: not the published file"
                )
            os.replace(part, target)
        except OSError as error:
            raise OutputError(f"cannot write {target}: {error.strerror or error}") from None
        finally:
            part.unlink(missing_ok=True)
        written.append(target)
    return written


def _sha256(path: Path) -> str:
    with path.open("rb") as handle:
        return hashlib.file_digest(handle, "sha256").hexdigest()
