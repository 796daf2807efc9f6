"""numba's compiled kernels, cached on disk where a change to the project cannot leave stale code.

numba's `cache=True` keys each cached function by its own source file alone. A kernel that calls
a compiled function of another module, or reads another module's constant, keeps the machine
code it was compiled with after that module changes: quiet_play's `play_quiet` inlines the movers'
`begin_edge`, and once kept the old edge speeds after the ladder cap was added there. So
`njit_cached` compiles as `numba.njit(cache=True, ...)` does, but into a cache folder named after
a fingerprint of every source file of the package: any change to them starts a fresh cache.

The folders live under `NUMBA_CACHE_DIR` if set, else the user's cache folder
(`$XDG_CACHE_HOME` or `~/.cache`), in `decoy/numba/<fingerprint>`; the `KEEP_CACHES` most
recently used are kept. Where no such folder can be written, kernels compile without a cache;
with NUMBA_DISABLE_JIT nothing is compiled or cached.
"""

from __future__ import annotations

import hashlib
import os
import shutil
import tempfile
from collections.abc import Callable
from functools import cache
from pathlib import Path
from typing import Any, TypeVar

PACKAGE = Path(__file__).resolve().parent
KEEP_CACHES = 8
"""Cache folders (fingerprints) kept: a few versions or edits back, not every one ever run."""
LAST_USED = "last-used"
"""The file whose modification time says when a cache folder was last used."""

F = TypeVar("F", bound=Callable[..., Any])


def fingerprint() -> str:
    """A digest of every source file of the package (names and contents)."""
    digest = hashlib.sha256()
    for path in sorted(PACKAGE.rglob("*.py")):
        digest.update(path.relative_to(PACKAGE).as_posix().encode())
        digest.update(path.read_bytes())
    return digest.hexdigest()[:16]


def cache_root() -> Path:
    """The folder holding one cache folder per fingerprint."""
    numba_dir = os.environ.get("NUMBA_CACHE_DIR")
    if numba_dir:
        return Path(numba_dir) / "decoy"
    user_cache = os.environ.get("XDG_CACHE_HOME") or str(Path.home() / ".cache")  # may raise
    return Path(user_cache) / "decoy" / "numba"


@cache
def cache_dir() -> str | None:
    """This code's cache folder, created and marked used (older ones beyond `KEEP_CACHES`
    removed); None where it cannot be written."""
    try:
        root = cache_root()
        folder = root / fingerprint()
        folder.mkdir(parents=True, exist_ok=True)
        tempfile.TemporaryFile(dir=folder).close()
        (folder / LAST_USED).touch()
    except (OSError, RuntimeError):  # RuntimeError: no home folder to be found
        return None
    _forget_old(root)
    return str(folder)


def _forget_old(root: Path) -> None:
    """Remove the cache folders beyond the `KEEP_CACHES` most recently used."""
    try:
        folders = [p for p in root.iterdir() if (p / LAST_USED).is_file()]
        folders.sort(key=lambda p: (p / LAST_USED).stat().st_mtime, reverse=True)
    except OSError:
        return
    for old in folders[KEEP_CACHES:]:
        shutil.rmtree(old, ignore_errors=True)


def jit_enabled() -> bool:
    """Whether numba compiles (not `NUMBA_DISABLE_JIT`, under which kernels run as Python)."""
    from numba.core import config

    return not config.DISABLE_JIT  # type: ignore[attr-defined]  # set at run time


def njit_cached(function: F | None = None, **options: Any) -> Any:
    """`numba.njit(cache=True, **options)` with this code's cache folder (module docstring);
    used bare (`@njit_cached`) or with options (`@njit_cached(nogil=True)`)."""
    from numba import njit
    from numba.core import config

    def compile_(fn: F) -> F:
        if config.DISABLE_JIT:  # type: ignore[attr-defined]  # plain Python: nothing to cache
            return njit(**options)(fn)
        folder = cache_dir()
        if folder is None:
            return njit(cache=False, **options)(fn)
        # numba's config sets its settings at run time, out of a type checker's sight
        previous = config.CACHE_DIR  # type: ignore[attr-defined]
        config.CACHE_DIR = folder  # type: ignore[attr-defined]  # its locator is chosen now
        try:
            return njit(cache=True, **options)(fn)
        finally:
            config.CACHE_DIR = previous  # type: ignore[attr-defined]

    return compile_ if function is None else compile_(function)
