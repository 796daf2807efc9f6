"""`decoy bench --baseline REF`: the same sections on this code and on a baseline, alternating.

Speed differs by several times between machines and from one hour to the next on a shared one,
so a speed-up is only meaningful as a ratio of runs made side by side. Every run here is a fresh
Python process that calls the bench sections of one code tree through `DRIVER` (which uses only
the bench API both trees have: `BenchConfig.create`, `check_damage_model`, `find_data`,
`run_section`), or, for the sections of `decoy_cli.bench.portable`, that file of the current
tree on the side's package; runs alternate current, baseline, current, baseline, ... and each
pair gives one ratio of the section's headline figures (`headlines`), reported as median, min
and max.

Either tree is asked only what it supports (`run_args`): `create` gets the switches every
version takes (the map only off the built-in one), Table 1's sizes are set on the config after
it (fields every version's `BenchConfig` has; a tree without one says so instead of measuring
something else), and the portable sections read the current code's sizes from their settings.

The baseline is a git ref of the checkout this code runs from (exported with `git archive` into
a folder beside the report, removed afterwards) or the Python interpreter of another environment
where another version is installed. Each run starts in an empty folder beside the report and
writes its result there atomically; a baseline that turns out to run the current code is an
error, not a ratio of 1.
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
import tempfile
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path

import decoy_cli
from decoy_cli.bench import portable
from decoy_cli.bench.portable import PORTABLE_SECTIONS
from decoy_cli.bench.records import BenchSwitches, RatioRecord, RunArgs, SideBySide
from decoy_cli.bench.runner import BenchConfig, portable_config
from decoy_cli.csgo import BUILTIN_MAP
from decoy_cli.damage import SHIPPED_CHOICES
from decoy_cli.errors import DecoyError
from decoy_cli.files import JsonObject, JsonValue, object_at, objects_in

DRIVER = """
import json, os, sys
if sys.path and sys.path[0] in ("", os.getcwd()):
    sys.path.pop(0)  # `python -c` puts the working folder first: only the tree's code may load
args = json.loads(sys.argv[1])
devnull = os.open(os.devnull, os.O_WRONLY)
os.dup2(devnull, 1)
import dataclasses
import decoy_cli
from decoy_cli.bench import BenchConfig, check_damage_model, find_data, run_section
from pathlib import Path
run = args["run"]
data = find_data(Path(args["data"])) if args["data"] else None
try:
    if args["portable"]:  # the current tree's file, run on this tree's package
        import importlib.util
        spec = importlib.util.spec_from_file_location("decoy_portable_bench", args["portable"])
        module = importlib.util.module_from_spec(spec)
        spec.loader.exec_module(module)
        section = module.PORTABLE_SECTIONS[args["section"]]
        result = section(run["portable"])
    else:  # the tree's own section, its model checked as its `decoy bench` would
        config = BenchConfig.create(**run["switches"])
        status = check_damage_model(run["switches"]["models"])
        fields = {field.name for field in dataclasses.fields(config)}
        lacking = sorted(set(run["sizes"]) - fields)
        if lacking:
            raise ValueError("this version's BenchConfig has no " + ", ".join(lacking))
        sizes = {k: tuple(v) if isinstance(v, list) else v for k, v in run["sizes"].items()}
        config = dataclasses.replace(config, **sizes)
        result = run_section(args["section"], config, status, data)
except Exception as error:
    result = {"error": f"{type(error).__name__}: {error}"}
result["code"] = decoy_cli.__file__
with open(args["result"] + ".part", "w") as handle:
    json.dump(result, handle)
os.replace(args["result"] + ".part", args["result"])
"""
"""Runs one section of whichever decoy_cli the interpreter imports; writes its JSON result."""

PORTABLE_FILE = Path(portable.__file__).resolve()
"""The portable sections' source, loaded by path in either tree's process."""

RUN_TIMEOUT_S = 3600
"""Wall-clock limit of one section run."""


@dataclass(frozen=True)
class CodeTree:
    """Where a side's code comes from: the interpreter, and a folder put first on its path."""

    label: str
    python: str
    path: Path | None
    numba_cache: Path | None = None
    """Where its compiled kernels are cached (an exported baseline's own folder, removed with
    it); None: where that code caches them."""


def current_tree() -> CodeTree:
    """This code, as the running interpreter imports it."""
    package_parent = Path(decoy_cli.__file__).resolve().parents[1]
    return CodeTree("current", sys.executable, package_parent)


@contextmanager
def baseline_tree(ref: str, work: Path) -> Iterator[CodeTree]:
    """The baseline while the block runs: the Python of another environment (a path to an
    interpreter), or a git ref of this checkout exported into a fresh folder in `work` that is
    removed afterwards, whatever happens. Neither is a DecoyError."""
    candidate = Path(ref)
    if candidate.is_file() and os.access(candidate, os.X_OK):
        yield CodeTree(f"python {candidate}", str(candidate), None)
        return
    root = _checkout_root()
    try:
        sha = _git(root, "rev-parse", "--verify", "--quiet", f"{ref}^{{commit}}").strip()
    except DecoyError:
        raise DecoyError(
            f"--baseline {ref}: neither a commit of this checkout nor an executable Python"
        ) from None
    archive = subprocess.run(
        ["git", "-C", str(root), "archive", "--format=tar", sha], capture_output=True, check=False
    )
    if archive.returncode != 0:
        raise DecoyError(f"--baseline {ref}: git archive failed: {archive.stderr.decode().strip()}")
    target = Path(tempfile.mkdtemp(prefix=f"baseline-{sha[:12]}-", dir=work))
    try:
        _extract(archive.stdout, target)
        if not (target / "decoy_cli" / "bench" / "__init__.py").is_file():
            raise DecoyError(f"--baseline {ref}: commit {sha[:12]} has no decoy_cli/bench to run")
        yield CodeTree(f"{ref} ({sha[:12]})", sys.executable, target, target / ".numba-cache")
    finally:
        shutil.rmtree(target, ignore_errors=True)


def _extract(archive: bytes, target: Path) -> None:
    """Unpack a tar of the repository's files, refusing any member that would land outside
    `target` (Python's "data" filter where this Python has it, the same check by hand before)."""
    with tarfile.open(fileobj=io.BytesIO(archive)) as tar:
        if hasattr(tarfile, "data_filter"):
            tar.extractall(target, filter="data")
            return
        for member in tar.getmembers():
            parts = Path(member.name).parts
            if member.name.startswith("/") or ".." in parts or member.issym() or member.islnk():
                raise DecoyError(f"the baseline archive holds an unsafe member: {member.name}")
        tar.extractall(target)  # every member checked above


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


def run_args(config: BenchConfig) -> RunArgs:
    """What either tree is given to run `config`'s sections (module docstring); a model folder
    made absolute, as the runs start in folders of their own."""
    models = str(config.models)
    if models not in (*SHIPPED_CHOICES, "none"):  # a folder, as the loader reads it
        models = str(Path(models).resolve())
    switches: BenchSwitches = {
        "quick": config.quick,
        "models": models,
        "mover": config.mover,
        "combat": config.combat,
        "bomb": config.bomb,
        "seed": config.seed,
    }
    if config.map_name != BUILTIN_MAP:  # only then: earlier versions know no map_name
        switches["map_name"] = config.map_name
    portable = portable_config(config)
    portable["models"] = models
    return {
        "switches": switches,
        "sizes": {"agent_counts": list(config.agent_counts), "decisions": config.decisions},
        "portable": portable,
    }


def run_in(tree: CodeTree, section: str, run: RunArgs, data: Path | None, work: Path) -> JsonObject:
    """One section in a fresh process of `tree`, in an empty folder of `work` removed after;
    its result, or {"error": one line}."""
    env = dict(os.environ)
    if tree.path is not None:
        env["PYTHONPATH"] = os.pathsep.join(
            [str(tree.path), *filter(None, [env.get("PYTHONPATH")])]
        )
    if tree.numba_cache is not None:
        env["NUMBA_CACHE_DIR"] = str(tree.numba_cache)
    scratch = Path(tempfile.mkdtemp(prefix="section-", dir=work))
    result = scratch / "result.json"
    args = {
        "run": run,
        "data": str(data) if data else None,
        "section": section,
        "result": str(result),
        "portable": str(PORTABLE_FILE) if section in PORTABLE_SECTIONS else None,
    }
    try:
        done = subprocess.run(
            [tree.python, "-c", DRIVER, json.dumps(args)],
            env=env,
            cwd=scratch,
            capture_output=True,
            text=True,
            timeout=RUN_TIMEOUT_S,
            check=False,
        )
        if not result.is_file():
            last = (done.stderr.strip().splitlines() or ["no output"])[-1]
            return {"error": f"{tree.label}: the section process failed: {last}"}
        loaded: JsonValue = json.loads(result.read_text())
    except (OSError, ValueError, subprocess.TimeoutExpired) as error:
        return {"error": f"{tree.label}: {error}"}
    finally:
        shutil.rmtree(scratch, ignore_errors=True)
    if not isinstance(loaded, dict):
        return {"error": f"{tree.label}: the section process wrote no JSON object"}
    if tree.path is not None and not str(loaded.get("code", "")).startswith(str(tree.path)):
        return {"error": f"{tree.label}: ran {loaded.get('code')}, not the code in {tree.path}"}
    return loaded


def headlines(section: str, result: JsonObject) -> dict[str, float]:
    """The figures a speed-up is the ratio of, higher is better (a time becomes a rate)."""
    if "error" in result or "skipped" in result:
        return {}
    figures: dict[str, JsonValue] = {}
    if section == "metrics":
        figures = {"pairs/s": result.get("pairs_per_s")}
        for row in objects_in(result.get("kernels")):
            figures[f"calls/s, {row.get('kernel')} {row.get('size')}"] = _per_s(row)
    elif section == "reader" and result.get("files"):
        figures = {"MB/s (JSON)": result.get("mb_per_s_decompressed")}
    elif section == "awpy":
        readers = object_at(result, "readers")
        figures = {f"rows/s, {k}": object_at(readers, k).get("rows_per_s") for k in readers}
    elif section == "replay" and result.get("rounds"):
        figures = {"rounds/s": result.get("rounds_per_s")}
    elif section == "kinematic":
        figures = {f"ticks/s, {result.get('agents')} agents": result.get("ticks_per_s")}
    elif section == "env":
        figures = {"agent decisions/s": result.get("decisions_per_s")}
        arrays = result.get("array_decisions_per_s", result.get("decisions_per_s"))
        figures["agent decisions/s, arrays (PettingZoo where absent)"] = arrays
    elif section == "table1":
        rows = objects_in(result.get("rows"))
        figures = {f"ticks/s, {row.get('agents')} agents": row.get("ticks_per_s") for row in rows}
    elif section == "combat_step":
        for row in objects_in(result.get("rows")):
            step = object_at(object_at(row, "parts"), "step")
            figures[f"steps/s, {row.get('agents')} agents, {row.get('layout')}"] = _per_s(step)
    return {k: float(v) for k, v in figures.items() if isinstance(v, int | float) and v > 0}


def _per_s(times: JsonObject) -> float | None:
    """The rate of a median time in milliseconds (None without one, or at zero)."""
    median = times.get("median_ms")
    return 1e3 / median if isinstance(median, int | float) and median else None


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

    def to_dict(self) -> RatioRecord:
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
    run: RunArgs,
    data: Path | None,
    current: CodeTree,
    baseline: CodeTree,
    repeats: int,
    work: Path,
    on_run: Callable[[str, str, int], None] = lambda section, side, repeat: None,
) -> SideBySide:
    """Each section `repeats` times on each side, alternating; raw results and the ratios."""
    runs: dict[str, dict[str, list[JsonObject]]] = {}
    ratios: list[Ratio] = []
    for section in sections:
        runs[section] = {"current": [], "baseline": []}
        for repeat in range(repeats):
            pair: dict[str, JsonObject] = {}
            for side, tree in (("current", current), ("baseline", baseline)):
                on_run(section, side, repeat)
                pair[side] = run_in(tree, section, run, data, work)
                runs[section][side].append(pair[side])
            code = {side: result.get("code") for side, result in pair.items()}
            if code["current"] is not None and code["current"] == code["baseline"]:
                raise DecoyError(  # found after the first pair, not after every repeat
                    f"the baseline ran the same code as the current side ({code['current']}): "
                    "give a commit, or the Python of an environment with another version installed"
                )
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
