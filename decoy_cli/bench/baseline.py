"""`decoy bench --baseline REF`: the same sections on this code and on a baseline, alternating.

Speed differs by several times between machines and from one hour to the next on a shared one,
so a speed-up is only meaningful as a ratio of runs made side by side. Every run here is a fresh
Python process that calls the bench sections of one code tree through `DRIVER` (which uses only
the bench API both trees have: `BenchConfig.create`, `check_damage_model`, `find_data`,
`run_section`); runs alternate current, baseline, current, baseline, ... and each pair gives one
ratio of the section's headline figures (`headlines`), reported as median, min and max.

The baseline is a git ref of the checkout this code runs from (exported with `git archive` into
a folder beside the report, removed afterwards) or the Python interpreter of another environment
where another version is installed.
"""

from __future__ import annotations

import io
import json
import os
import shutil
import statistics
import subprocess
import sys
import tarfile
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import decoy_cli
from decoy_cli.errors import DecoyError

DRIVER = """
import json, os, sys
args = json.loads(sys.argv[1])
devnull = os.open(os.devnull, os.O_WRONLY)
os.dup2(devnull, 1)
import decoy_cli
from decoy_cli.bench import BenchConfig, check_damage_model, find_data, run_section
from pathlib import Path
config = BenchConfig.create(**args["config"])
status = check_damage_model(args["config"]["models"])
data = find_data(Path(args["data"])) if args["data"] else None
try:
    result = run_section(args["section"], config, status, data)
except Exception as error:
    result = {"error": f"{type(error).__name__}: {error}"}
result["code"] = decoy_cli.__file__
with open(args["result"], "w") as handle:
    json.dump(result, handle)
"""
"""Runs one section of whichever decoy_cli the interpreter imports; writes its JSON result."""

RUN_TIMEOUT_S = 3600
"""Wall-clock limit of one section run."""


@dataclass(frozen=True)
class CodeTree:
    """Where a side's code comes from: the interpreter, and a folder put first on its path."""

    label: str
    python: str
    path: Path | None


def current_tree() -> CodeTree:
    """This code, as the running interpreter imports it."""
    package_parent = Path(decoy_cli.__file__).resolve().parents[1]
    return CodeTree("current", sys.executable, package_parent)


def baseline_tree(ref: str, work: Path) -> CodeTree:
    """The baseline: the Python of another environment (a path to an interpreter), or a git
    ref of this checkout exported into `work`. A ref that does not resolve, or no checkout, is
    a DecoyError."""
    candidate = Path(ref)
    if candidate.is_file() and os.access(candidate, os.X_OK):
        return CodeTree(f"python {candidate}", str(candidate), None)
    root = _checkout_root()
    sha = _git(root, "rev-parse", "--verify", "--quiet", f"{ref}^{{commit}}").strip()
    archive = subprocess.run(
        ["git", "-C", str(root), "archive", "--format=tar", sha],
        capture_output=True,
        check=False,
    )
    if archive.returncode != 0:
        raise DecoyError(f"--baseline {ref}: git archive failed: {archive.stderr.decode().strip()}")
    target = work / f"baseline-{sha[:12]}"
    if target.exists():
        shutil.rmtree(target)
    target.mkdir(parents=True)
    with tarfile.open(fileobj=io.BytesIO(archive.stdout)) as tar:
        tar.extractall(target, filter="data")
    if not (target / "decoy_cli" / "bench" / "__init__.py").is_file():
        raise DecoyError(f"--baseline {ref}: commit {sha[:12]} has no decoy_cli/bench to run")
    return CodeTree(f"{ref} ({sha[:12]})", sys.executable, target)


def _checkout_root() -> Path:
    package = Path(decoy_cli.__file__).resolve().parent
    try:
        return Path(_git(package, "rev-parse", "--show-toplevel").strip())
    except DecoyError:
        raise DecoyError(
            "--baseline REF needs this code to run from a git checkout; otherwise give the "
            "Python interpreter of an environment with the baseline installed"
        ) from None


def _git(where: Path, *args: str) -> str:
    try:
        done = subprocess.run(
            ["git", "-C", str(where), *args], capture_output=True, text=True, check=False
        )
    except OSError as error:
        raise DecoyError(f"cannot run git: {error}") from None
    if done.returncode != 0:
        detail = done.stderr.strip() or f"git {' '.join(args)} failed"
        raise DecoyError(f"--baseline: {detail}")
    return done.stdout


def run_in(tree: CodeTree, section: str, config: dict[str, Any], data: Path | None, result: Path):
    """One section in a fresh process of `tree`; its result, or {"error": one line}."""
    env = dict(os.environ)
    if tree.path is not None:
        env["PYTHONPATH"] = os.pathsep.join(
            [str(tree.path), *filter(None, [env.get("PYTHONPATH")])]
        )
    args = {
        "config": config,
        "data": str(data) if data else None,
        "section": section,
        "result": str(result),
    }
    result.unlink(missing_ok=True)
    try:
        done = subprocess.run(
            [tree.python, "-c", DRIVER, json.dumps(args)],
            env=env,
            cwd=result.parent,  # not the caller's folder: `python -c` imports from there first
            capture_output=True,
            text=True,
            timeout=RUN_TIMEOUT_S,
            check=False,
        )
    except (OSError, subprocess.TimeoutExpired) as error:
        return {"error": f"{tree.label}: {error}"}
    if not result.is_file():
        last = (done.stderr.strip().splitlines() or ["no output"])[-1]
        return {"error": f"{tree.label}: the section process failed: {last}"}
    loaded: dict[str, Any] = json.loads(result.read_text())
    result.unlink()
    if tree.path is not None and not str(loaded.get("code", "")).startswith(str(tree.path)):
        return {"error": f"{tree.label}: ran {loaded.get('code')}, not the code in {tree.path}"}
    return loaded


def headlines(section: str, result: dict[str, Any]) -> dict[str, float]:
    """The figures a speed-up is the ratio of, higher is better (a time becomes a rate)."""
    if "error" in result or "skipped" in result:
        return {}
    if section == "metrics":
        return {"pairs/s": result["pairs_per_s"]}
    if section == "reader":
        return {"MB/s (JSON)": result["mb_per_s_decompressed"]} if result.get("files") else {}
    if section == "replay":
        return {"rounds/s": result["rounds_per_s"]} if result.get("rounds") else {}
    if section == "table1":
        return {f"ticks/s, {row['agents']} agents": row["ticks_per_s"] for row in result["rows"]}
    if section == "combat_step":
        return {
            f"steps/s, {row['layout']}": 1e3 / row["parts"]["step"]["median_ms"]
            for row in result["rows"]
        }
    return {}


@dataclass(frozen=True)
class Ratio:
    """One headline figure on both sides, and the ratios of the alternating pairs."""

    section: str
    figure: str
    current: list[float]
    baseline: list[float]

    @property
    def ratios(self) -> list[float]:
        return [c / b for c, b in zip(self.current, self.baseline, strict=True) if b > 0]

    def to_dict(self) -> dict[str, Any]:
        ratios = self.ratios
        return {
            "section": self.section,
            "figure": self.figure,
            "current": self.current,
            "baseline": self.baseline,
            "ratios": ratios,
            "ratio_median": statistics.median(ratios) if ratios else None,
            "ratio_min": min(ratios) if ratios else None,
            "ratio_max": max(ratios) if ratios else None,
        }


def side_by_side(
    sections: list[str],
    config: dict[str, Any],
    data: Path | None,
    current: CodeTree,
    baseline: CodeTree,
    repeats: int,
    work: Path,
    on_run: Callable[[str, str, int], None] = lambda section, side, repeat: None,
) -> dict[str, Any]:
    """Each section `repeats` times on each side, alternating; raw results and the ratios."""
    runs: dict[str, dict[str, list[dict[str, Any]]]] = {}
    ratios: list[Ratio] = []
    result_file = work / "section-result.json"
    for section in sections:
        runs[section] = {"current": [], "baseline": []}
        for repeat in range(repeats):
            for side, tree in (("current", current), ("baseline", baseline)):
                on_run(section, side, repeat)
                runs[section][side].append(run_in(tree, section, config, data, result_file))
        figures_c = [headlines(section, r) for r in runs[section]["current"]]
        figures_b = [headlines(section, r) for r in runs[section]["baseline"]]
        for figure in figures_c[0] if figures_c else {}:
            if all(figure in f for f in figures_c + figures_b):
                ratios.append(
                    Ratio(
                        section,
                        figure,
                        [f[figure] for f in figures_c],
                        [f[figure] for f in figures_b],
                    )
                )
    return {
        "current": current.label,
        "baseline": baseline.label,
        "repeats": repeats,
        "runs": runs,
        "ratios": [r.to_dict() for r in ratios],
        "errors": [
            f"{section} ({side}): {r['error']}"
            for section, sides in runs.items()
            for side, results in sides.items()
            for r in results
            if "error" in r
        ],
    }
