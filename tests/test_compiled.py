"""numba's cache kept honest (decoy_cli/compiled.py): one cache folder per fingerprint of the
package's sources, so a change to any module (a callee a kernel inlines, a constant it reads)
starts a fresh cache instead of leaving stale machine code."""

from __future__ import annotations

import os
import time
from pathlib import Path

import numpy as np
import pytest

from decoy_cli import compiled


@pytest.fixture
def cache_root(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Path:
    """A fresh NUMBA_CACHE_DIR for this test (the folder of `cache_dir` forgotten before and
    after, so other tests go on with the real one)."""
    monkeypatch.setenv("NUMBA_CACHE_DIR", str(tmp_path))
    compiled.cache_dir.cache_clear()
    yield tmp_path / "decoy"
    compiled.cache_dir.cache_clear()


def test_the_fingerprint_follows_every_source_file(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    package = tmp_path / "pkg"
    (package / "sub").mkdir(parents=True)
    (package / "kernels.py").write_text("SPEED = 1.0\n")
    (package / "sub" / "caller.py").write_text("from pkg.kernels import SPEED\n")
    monkeypatch.setattr(compiled, "PACKAGE", package)
    first = compiled.fingerprint()
    assert compiled.fingerprint() == first
    (package / "kernels.py").write_text("SPEED = 0.78\n")  # the callee changes
    second = compiled.fingerprint()
    assert second != first
    (package / "sub" / "other.py").write_text("")  # a new module
    assert compiled.fingerprint() not in (first, second)


def test_kernels_are_cached_in_the_folder_of_this_code(cache_root: Path) -> None:
    from numba import njit

    @compiled.njit_cached
    def doubled(values):
        return values * 2.0

    @compiled.njit_cached(nogil=True)
    def summed(values):
        return values.sum()

    values = np.arange(4.0)
    np.testing.assert_array_equal(doubled(values), values * 2.0)
    assert summed(values) == 6.0
    folder = cache_root / compiled.fingerprint()
    assert (folder / compiled.LAST_USED).is_file()
    cached = [p.name for p in folder.rglob("*.nbi")]
    assert any("doubled" in name for name in cached) and any("summed" in name for name in cached)
    assert doubled.stats.cache_path.startswith(str(folder))
    assert summed.targetoptions.get("nogil") and not doubled.targetoptions.get("nogil")

    @njit(cache=True)
    def tripled(values):  # numba's own caching, for other code: not in decoy's folder
        return values * 3.0

    assert not tripled.stats.cache_path.startswith(str(folder))


def test_without_a_writable_folder_kernels_compile_uncached(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    blocked = tmp_path / "file"
    blocked.write_text("not a folder")
    monkeypatch.setenv("NUMBA_CACHE_DIR", str(blocked))
    compiled.cache_dir.cache_clear()
    try:
        assert compiled.cache_dir() is None

        @compiled.njit_cached
        def plus_one(x):
            return x + 1

        assert plus_one(1) == 2
        assert plus_one.stats.cache_path is None  # no cache behind it
    finally:
        compiled.cache_dir.cache_clear()


def test_only_the_most_recently_used_folders_are_kept(cache_root: Path) -> None:
    now = time.time()
    for k in range(compiled.KEEP_CACHES + 3):
        old = cache_root / f"old{k:02d}"
        old.mkdir(parents=True)
        (old / compiled.LAST_USED).touch()
        os.utime(old / compiled.LAST_USED, (now - 1000 + k, now - 1000 + k))
    (cache_root / "not ours").mkdir()  # no marker: left alone
    current = Path(str(compiled.cache_dir()))
    kept = sorted(p.name for p in cache_root.iterdir() if (p / compiled.LAST_USED).is_file())
    assert len(kept) == compiled.KEEP_CACHES and current.name in kept
    newest = [f"old{k:02d}" for k in range(compiled.KEEP_CACHES + 3)][-compiled.KEEP_CACHES + 1 :]
    assert [name for name in kept if name.startswith("old")] == newest
    assert (cache_root / "not ours").is_dir()


def test_without_numba_cache_dir_the_folder_is_in_the_users_cache(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.delenv("NUMBA_CACHE_DIR", raising=False)
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path))
    assert compiled.cache_root() == tmp_path / "decoy" / "numba"
    monkeypatch.delenv("XDG_CACHE_HOME")
    monkeypatch.setenv("HOME", str(tmp_path / "home"))
    assert compiled.cache_root() == tmp_path / "home" / ".cache" / "decoy" / "numba"


def test_no_home_folder_means_no_cache(monkeypatch: pytest.MonkeyPatch) -> None:
    def nowhere() -> Path:
        raise RuntimeError("Could not determine home directory.")

    monkeypatch.delenv("NUMBA_CACHE_DIR", raising=False)
    monkeypatch.delenv("XDG_CACHE_HOME", raising=False)
    monkeypatch.setattr(Path, "home", nowhere)
    compiled.cache_dir.cache_clear()
    try:
        assert compiled.cache_dir() is None
    finally:
        compiled.cache_dir.cache_clear()


def test_with_the_jit_disabled_nothing_is_cached(
    cache_root: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    from numba.core import config

    monkeypatch.setattr(config, "DISABLE_JIT", True)

    @compiled.njit_cached
    def plus_two(x):
        return x + 2

    assert plus_two(1) == 3
    assert not cache_root.exists()
