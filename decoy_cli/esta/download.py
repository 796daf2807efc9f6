"""Download ESTA match files by id from the public ESTA repository, verified, atomically.

ESTA (P. Xenopoulos et al., github.com/pnxenopoulos/esta, CC BY-SA 4.0) keeps one xz-compressed
awpy 1.x JSON per match in the git repository itself (no Git LFS): `data/lan/<uuid>.json.xz`
(680 LAN matches) and `data/online/<uuid>.json.xz` (878 online matches), 1-3 MB each. GitHub
serves them raw at `https://raw.githubusercontent.com/pnxenopoulos/esta/main/data/<subset>/
<uuid>.json.xz`, which is `ESTA_BASE_URL` + `/<subset>/<uuid>.json.xz`. An id is the uuid
(looked up in `lan/`, then `online/`) or `lan/<uuid>` / `online/<uuid>`; another base URL (a
mirror, a pinned commit such as `.../pnxenopoulos/esta/<commit>/data`, or a `file://` folder)
must keep the `<subset>/<uuid>.json.xz` layout below it. The repository publishes no
checksums: the sha256 of every verified file is reported so that a user can pin it, and an
expected sha256 can be given.

A download is streamed to a hidden temporary file beside the target and verified before it is
renamed into place: the body is complete (as long as its Content-Length), its sha256 matches when
one is expected, it is xz data that decompresses, the reader parses it as an ESTA match with at
least one readable round, and the match is on the asked map (de_dust2 by default). Anything else is
one DownloadError line and the temporary file is removed, so the folder only ever holds verified
matches. A target that is already present and verifies is not downloaded again.
"""

from __future__ import annotations

import hashlib
import http.client
import os
import re
import tempfile
import urllib.error
import urllib.parse
import urllib.request
import urllib.response
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import BinaryIO

from decoy_cli import __version__
from decoy_cli.csgo import BUILTIN_MAP
from decoy_cli.errors import DownloadError, EstaError, OutputError
from decoy_cli.esta.reader import read_match
from decoy_cli.esta.source import XZ_MAGIC

ESTA_BASE_URL = "https://raw.githubusercontent.com/pnxenopoulos/esta/main/data"
"""Raw files of the ESTA repository's default branch, above the `lan/` and `online/` folders."""

SUBSETS = ("lan", "online")
"""ESTA's folders under `data/`, in the order a bare id is looked up."""

DEFAULT_DEST = Path("decoy-out") / "data" / "esta"
"""Where downloaded matches go unless told otherwise (`decoy evaluate` can be pointed at it)."""

MAP_NAME = BUILTIN_MAP
SUFFIX = ".json.xz"
CHUNK_BYTES = 1 << 16
LFS_POINTER = b"version https://git-lfs.github.com/spec/"

_ID = re.compile(r"(?:(?P<subset>lan|online)/)?(?P<name>[A-Za-z0-9][A-Za-z0-9_-]{0,127})")
_SHA256 = re.compile(r"[0-9a-f]{64}")

Response = http.client.HTTPResponse | urllib.response.addinfourl
"""What `urlopen` returns: an HTTP response, or a file's for a file:// URL."""

ProgressCallback = Callable[[int, int | None], None]
"""Called with (bytes received so far, total bytes or None when the server does not say)."""


@dataclass(frozen=True)
class MatchRef:
    """A match id: the file name stem, and the ESTA folder if the id named one."""

    name: str
    subset: str | None

    @property
    def file_name(self) -> str:
        return self.name + SUFFIX


@dataclass(frozen=True)
class Downloaded:
    """A verified match file in place: "downloaded", "present" (kept) or "replaced"."""

    match_id: str
    path: Path
    status: str
    url: str | None
    size: int
    sha256: str
    rounds: int
    note: str = ""


def parse_match_id(text: str) -> MatchRef:
    """`<uuid>`, `lan/<uuid>` or `online/<uuid>` (a trailing .json.xz is allowed)."""
    match = _ID.fullmatch(text.strip().removesuffix(SUFFIX))
    if match is None:
        raise DownloadError(
            f"{text!r} is not an ESTA match id (expected a uuid, lan/<uuid> or online/<uuid>)"
        )
    return MatchRef(name=match["name"], subset=match["subset"])


def parse_sha256(text: str) -> str:
    """A sha256 as 64 lowercase hex digits."""
    digest = text.strip().lower()
    if not _SHA256.fullmatch(digest):
        raise DownloadError(f"{text!r} is not a sha256 (64 hexadecimal digits)")
    return digest


def match_urls(ref: MatchRef, base_url: str = ESTA_BASE_URL) -> list[str]:
    """The URLs to try for a match, in order: its own folder, or `lan/` then `online/`."""
    base = base_url.rstrip("/")
    subsets = (ref.subset,) if ref.subset else SUBSETS
    return [f"{base}/{subset}/{ref.file_name}" for subset in subsets]


def verify_file(
    path: str | Path, sha256: str | None = None, map_name: str = MAP_NAME
) -> tuple[str, int]:
    """Check a match file on disk (module doc); returns its sha256 and readable rounds."""
    path = Path(path)
    try:
        with path.open("rb") as source:
            head = source.read(len(LFS_POINTER))
            source.seek(0)
            digest = hashlib.file_digest(source, "sha256").hexdigest()
    except OSError as error:
        raise DownloadError(f"cannot read {path}: {error.strerror or error}") from None
    return _verify(path, digest, head, sha256, map_name)


def _verify(
    path: Path, digest: str, head: bytes, expected: str | None, map_name: str
) -> tuple[str, int]:
    """The checks after the body is complete: checksum, xz, ESTA, map."""
    if expected is not None and digest != expected:
        raise DownloadError(f"sha256 mismatch: expected {expected}, got {digest}")
    if head.startswith(LFS_POINTER):
        raise DownloadError(
            "got a Git LFS pointer, not the file (use a base URL that serves the file content)"
        )
    if not head.startswith(XZ_MAGIC):
        raise DownloadError(f"not xz data (starts with {head[:16]!r}): not an ESTA .json.xz file")
    try:
        match = read_match(path)
    except EstaError as error:
        raise DownloadError(f"not a readable ESTA match: {_without_path(error, path)}") from None
    if match.map_name != map_name:
        raise DownloadError(f"a {match.map_name or 'map-less'} match, not {map_name}: not kept")
    if not match.rounds:
        raise DownloadError(f"no readable round in the match ({len(match.round_errors)} broken)")
    return digest, len(match.rounds)


def _without_path(error: EstaError, path: Path) -> str:
    """The reader's message without the temporary file name it starts with."""
    return str(error).removeprefix(f"{path}: ")


def download_match(
    match_id: str,
    dest: str | Path = DEFAULT_DEST,
    base_url: str = ESTA_BASE_URL,
    sha256: str | None = None,
    timeout: float = 60.0,
    on_progress: ProgressCallback | None = None,
    map_name: str = MAP_NAME,
) -> Downloaded:
    """Fetch, verify and place one match as `dest/<uuid>.json.xz` (module doc).

    Every failure is one DownloadError (network, HTTP, verification) or OutputError (the
    destination) line that starts with the id.
    """
    try:
        ref = parse_match_id(match_id)
        expected = parse_sha256(sha256) if sha256 is not None else None
    except DownloadError as error:
        raise DownloadError(f"{match_id}: {error}") from None
    dest = Path(dest)
    target = dest / ref.file_name
    note = ""
    if target.is_file():
        try:
            digest, rounds = verify_file(target, expected, map_name)
        except DownloadError as error:
            note = f"the file there failed verification ({error})"
        else:
            return Downloaded(
                match_id, target, "present", None, target.stat().st_size, digest, rounds
            )
    try:
        dest.mkdir(parents=True, exist_ok=True)
        fd, name = tempfile.mkstemp(prefix=f".{ref.file_name}.", suffix=".part", dir=dest)
    except OSError as error:
        raise OutputError(
            f"{match_id}: cannot write to {dest}: {error.strerror or error}"
        ) from None
    tmp = Path(name)
    try:
        with os.fdopen(fd, "wb") as out:
            url, digest, head = _fetch_first(ref, match_id, base_url, out, timeout, on_progress)
        try:
            digest, rounds = _verify(tmp, digest, head, expected, map_name)
        except DownloadError as error:
            raise DownloadError(f"{match_id}: {url}: {error}") from None
        os.chmod(tmp, 0o644)
        os.replace(tmp, target)
    except OSError as error:
        raise OutputError(f"{match_id}: cannot write {target}: {error.strerror or error}") from None
    finally:
        tmp.unlink(missing_ok=True)
    status = "replaced" if note else "downloaded"
    return Downloaded(match_id, target, status, url, target.stat().st_size, digest, rounds, note)


def _fetch_first(
    ref: MatchRef,
    match_id: str,
    base_url: str,
    out: BinaryIO,
    timeout: float,
    on_progress: ProgressCallback | None,
) -> tuple[str, str, bytes]:
    """Stream the first URL that has the match into `out`: (url, sha256, first bytes)."""
    urls = match_urls(ref, base_url)
    for url in urls:
        response = open_url(url, match_id, timeout)
        if response is None:
            continue
        with response:
            digest, head = stream_body(response, url, match_id, out, timeout, on_progress)
        return url, digest, head
    raise DownloadError(f"{match_id}: not found (HTTP 404) at {' or '.join(urls)}")


def open_url(url: str, label: str, timeout: float) -> Response | None:
    """The open response, or None when the server has no such file; failures are one
    DownloadError line that starts with `label` (what is being fetched)."""
    request = urllib.request.Request(url, headers={"User-Agent": f"decoy/{__version__}"})
    try:
        return urllib.request.urlopen(request, timeout=timeout)
    except urllib.error.HTTPError as error:
        error.close()
        if error.code == 404:
            return None
        raise DownloadError(f"{label}: HTTP {error.code} {error.reason} from {url}") from None
    except urllib.error.URLError as error:
        if isinstance(error.reason, FileNotFoundError):  # file:// base URL
            return None
        if isinstance(error.reason, TimeoutError):
            raise DownloadError(f"{label}: no answer from {url} within {timeout:g} s") from None
        reason = getattr(error.reason, "strerror", None) or error.reason
        raise DownloadError(f"{label}: cannot reach {_host(url)}: {reason}") from None
    except TimeoutError:
        raise DownloadError(f"{label}: no answer from {url} within {timeout:g} s") from None
    except (http.client.HTTPException, OSError) as error:
        raise DownloadError(f"{label}: {url}: {_describe(error)}") from None


def stream_body(
    response: Response,
    url: str,
    label: str,
    out: BinaryIO,
    timeout: float,
    on_progress: ProgressCallback | None,
) -> tuple[str, bytes]:
    """Copy the body to `out`, hashing it: (sha256, first bytes); a short or stalled body raises
    DownloadError."""
    length = response.headers.get("Content-Length")
    total = int(length) if length and length.isdigit() else None
    digest = hashlib.sha256()
    head = b""
    received = 0
    try:
        while chunk := response.read(CHUNK_BYTES):
            if len(head) < len(LFS_POINTER):
                head += chunk[: len(LFS_POINTER) - len(head)]
            digest.update(chunk)
            out.write(chunk)
            received += len(chunk)
            if on_progress is not None:
                on_progress(received, total)
    except http.client.IncompleteRead as error:
        received += len(error.partial)
        raise DownloadError(
            f"{label}: download cut short after {received:,} bytes from {url}"
        ) from None
    except TimeoutError:
        raise DownloadError(
            f"{label}: {url} stopped sending for {timeout:g} s after {received:,} bytes"
        ) from None
    except (http.client.HTTPException, ConnectionError) as error:
        raise DownloadError(
            f"{label}: download from {url} failed after {received:,} bytes: {_describe(error)}"
        ) from None
    if total is not None and received != total:
        raise DownloadError(
            f"{label}: download cut short: {received:,} of {total:,} bytes from {url}"
        )
    return digest.hexdigest(), head


def _host(url: str) -> str:
    return urllib.parse.urlsplit(url).netloc or url


def _describe(error: BaseException) -> str:
    return getattr(error, "strerror", None) or str(error) or type(error).__name__
