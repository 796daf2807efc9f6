"""Every script of benchmarks/ that the README, the docs, the model cards or the code name exists
where they name it (CHANGELOG.md, the history, names scripts where they were then)."""

from __future__ import annotations

import re
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
CITED = re.compile(r"benchmarks/[a-z0-9_/]+\.py")


def _citing_files() -> list[Path]:
    files = [ROOT / "README.md", *(ROOT / "docs").glob("*.md"), *(ROOT / "models").glob("*.md")]
    for folder in ("decoy_cli", "tests", "benchmarks", "examples", "scripts"):
        files += (ROOT / folder).rglob("*.py")
    return [f for f in files if f.is_file()]


def test_every_cited_benchmark_script_exists() -> None:
    missing = sorted(
        f"{path.relative_to(ROOT)}: {name}"
        for path in _citing_files()
        for name in set(CITED.findall(path.read_text(encoding="utf-8")))
        if not (ROOT / name).is_file()
    )
    assert missing == []


def test_benchmarks_are_sorted_by_kind() -> None:
    """Scripts live in bench/, profile/, faults/ or studies/, none loose at the top."""
    kinds = {"bench", "profile", "faults", "studies"}
    folders = {p.name for p in (ROOT / "benchmarks").iterdir() if p.is_dir()}
    loose = [p.name for p in (ROOT / "benchmarks").glob("*.py")]
    assert folders - {"__pycache__"} <= kinds
    assert loose == []
