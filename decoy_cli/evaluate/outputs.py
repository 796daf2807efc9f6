"""Write an evaluation's outputs: the CSV tables, summary.json, the figures and report.md.

Every file is written atomically; a file that cannot be written (a full disk) is one
OutputError, and what was written before it stays. Every output is written on every run (empty
tables keep their header), so a folder never mixes files of two runs.

Layout of the output folder:

* `players.csv` (one row per player-round), `rounds.csv`, `failures.csv`;
* `tables/`: `trajectory.csv`, `unevaluated.csv`, `combat.csv`, `death_counts.csv`,
  `outcome_winner_confusion.csv`, `outcome_reason_confusion.csv`, `hp_over_time.csv`,
  `places.csv`, `bomb.csv`, `bomb_plant_confusion.csv`, `bomb_defuse_confusion.csv` (the bomb
  tables have only their header when the bomb was off);
* `summary.json`: what was run and every aggregate table;
* `figures/`: see decoy_cli/evaluate/figures.py; `report.md` (decoy_cli/evaluate/report.py)
  shows them all (no figures with `--no-figures`; an earlier run's are removed then);
* `view.html`: the page to look at any round, real against replay (decoy_cli/view/page.py;
  none with `--no-view`);
* `cache/`: the per-round results (decoy_cli/evaluate/cache.py).
"""

from __future__ import annotations

import fcntl
import os
import shutil
import signal
import threading
from collections import Counter
from collections.abc import Iterator
from contextlib import contextmanager, suppress
from pathlib import Path

import pandas as pd

from decoy_cli.errors import OutputError
from decoy_cli.evaluate.cache import CACHE_DIR
from decoy_cli.evaluate.figures import FIGURES, FIGURES_DIR, draw_figures
from decoy_cli.evaluate.record import WARNING_SEPARATOR
from decoy_cli.evaluate.report import (
    RunInfo,
    data_kind,
    mechanics,
    model_lines,
    report_markdown,
    run_counts,
    sight_line,
    world_line,
)
from decoy_cli.evaluate.runner import Evaluation
from decoy_cli.evaluate.tables import Tables
from decoy_cli.evaluate.view_page import run_page
from decoy_cli.files import (
    JsonObject,
    JsonValue,
    json_object,
    json_ready,
    staged,
    write_atomic,
    write_csv,
    write_json,
)
from decoy_cli.text import visible
from decoy_cli.view.page import write_page

FAILURE_COLUMNS = ("file", "round", "kind", "message")

VIEW_PAGE = "view.html"
"""The run's view page (decoy_cli/view/page.py), beside report.md."""


LOCK_FILE = ".decoy-evaluate.lock"
"""The lock of an output folder: a file the run writing to the folder holds an exclusive
`flock` on (and writes its process id into, for the message of a refused run)."""


@contextmanager
def output_lock(out: Path) -> Iterator[None]:
    """Hold the output folder for this run: a second run into the same folder (while this one
    lives) is one clear error instead of two runs overwriting each other's results.

    The lock is the kernel's (`flock`), so it ends with the process however it ends (a
    SIGKILL, a power cut): a lock file left by a run that no longer exists never stops the
    next, whatever process id it names. The file stays (removing it would let two runs lock
    two files). Holding the lock, the run removes what a killed run left half-done: staging
    folders and the cache's temporary files."""
    try:
        out.mkdir(parents=True, exist_ok=True)
        fd = os.open(out / LOCK_FILE, os.O_RDWR | os.O_CREAT, 0o644)
    except OSError as error:
        raise OutputError(f"cannot write into {out}: {error.strerror or error}") from None
    try:
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            owner = os.pread(fd, 32, 0).decode(errors="replace").strip()
            process = f" (process {owner})" if owner.isdigit() else ""
            raise OutputError(
                f"{out}: another decoy evaluate{process} is writing to this folder; wait for "
                "it or choose another --out"
            ) from None
        try:
            os.ftruncate(fd, 0)
            os.pwrite(fd, f"{os.getpid()}\n".encode(), 0)
        except OSError as error:
            reason = error.strerror or error
            raise OutputError(f"cannot write {out / LOCK_FILE}: {reason}") from None
        clear_leftovers(out)
        yield
    finally:
        os.close(fd)  # releases the lock


def clear_leftovers(out: Path) -> None:
    """Remove the staging folders and the cache's temporary files a killed run left in `out`
    (only the holder of the folder's lock may: no other run is writing there)."""
    for stage in out.glob(".staging-*"):
        shutil.rmtree(stage, ignore_errors=True)
    for folder in (out / CACHE_DIR / "rounds", out / CACHE_DIR / "index"):
        for temporary in folder.glob(".*.tmp"):
            temporary.unlink(missing_ok=True)


def write_outputs(
    evaluation: Evaluation,
    tables: Tables,
    out: Path,
    info: RunInfo,
    *,
    view: bool = True,
    figures: bool = True,
) -> list[Path]:
    """Write every output (see the module docstring; `view.html` unless `view` is off, the
    figures unless `figures` is off, and an earlier run's are removed then) as one set: into a
    staging folder first,
    then moved into `out` together, so a failure never leaves new tables beside an old report.
    A Ctrl-C takes effect once the set is in place (`ctrl_c_deferred`: stopped in the middle,
    matplotlib can fail with an error of its own). Only a SIGKILL or a power cut during the
    moves can leave a mix; the next run (every round cached) writes the set again. Returns the
    paths written."""
    with ctrl_c_deferred():
        return _write_and_publish(evaluation, tables, out, info, view, figures)


@contextmanager
def ctrl_c_deferred() -> Iterator[None]:
    """Hold a Ctrl-C (SIGINT) back until the block ends, then raise it as KeyboardInterrupt;
    outside the main thread (where Python handles signals) the block runs as it is."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    pressed: list[int] = []
    previous = signal.signal(signal.SIGINT, lambda number, _: pressed.append(number))
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, previous)
    if pressed:
        raise KeyboardInterrupt


def _write_and_publish(
    evaluation: Evaluation, tables: Tables, out: Path, info: RunInfo, view: bool, figures: bool
) -> list[Path]:
    with staged(out) as stage:
        written = _write_outputs(evaluation, tables, stage, info, figures)
        if view:
            written.append(write_page(stage / VIEW_PAGE, run_page(stage, cache_root=out)))
    if not view:
        (out / VIEW_PAGE).unlink(missing_ok=True)
    if not figures:  # an earlier run's figures would not be this run's
        for name in FIGURES.values():
            (out / FIGURES_DIR / name).unlink(missing_ok=True)
        with suppress(OSError):  # absent, or holding files that are not ours
            (out / FIGURES_DIR).rmdir()
    return [out / path.relative_to(stage) for path in written]


def _write_outputs(
    evaluation: Evaluation, tables: Tables, out: Path, info: RunInfo, figures: bool
) -> list[Path]:
    from decoy_cli.world.navmesh import load_navmesh

    written = [
        _csv(out / "players.csv", tables.players),
        _csv(out / "rounds.csv", tables.rounds),
        _csv(out / "failures.csv", failures_frame(evaluation)),
    ]
    folder = out / "tables"
    frames = {
        "trajectory": tables.trajectory,
        "unevaluated": tables.summary.unevaluated,
        "combat": tables.combat,
        "death_counts": pd.DataFrame([tables.deaths.counts]),
        "outcome_winner_confusion": _confusion(tables, "winner_confusion"),
        "outcome_reason_confusion": _confusion(tables, "end_reason_confusion"),
        "hp_over_time": tables.hp_curve,
        "places": tables.places,
        "bomb": tables.bomb.table() if tables.bomb else pd.DataFrame(columns=BOMB_TABLE_COLUMNS),
        "bomb_plant_confusion": _bomb_confusion(tables, "plant_confusion"),
        "bomb_defuse_confusion": _bomb_confusion(tables, "defuse_confusion"),
    }
    written += [_csv(folder / f"{name}.csv", frame) for name, frame in frames.items()]
    written.append(
        write_json(out / "summary.json", summary(evaluation, tables, info), sort_keys=False)
    )
    drawn: dict[str, Path] = {}
    if figures:
        nav = load_navmesh(evaluation.settings.map_name)
        drawn = draw_figures(out / FIGURES_DIR, evaluation.accumulator, tables, nav)
    written += list(drawn.values())
    text = report_markdown(
        evaluation, tables, info, {k: p.relative_to(out) for k, p in drawn.items()}
    )
    written.append(write_atomic(out / "report.md", visible(text, keep="\n").encode()))
    return written


def failures_frame(evaluation: Evaluation) -> pd.DataFrame:
    rows = [f.row() for f in evaluation.failures]
    return pd.DataFrame(rows, columns=list(FAILURE_COLUMNS)).astype({"round": "Int64"})


def _confusion(tables: Tables, name: str) -> pd.DataFrame:
    matrix = getattr(tables.outcome, name, None) if tables.outcome is not None else None
    if matrix is None:
        return pd.DataFrame(columns=["original"])
    return matrix.reset_index()


BOMB_TABLE_COLUMNS = ("metric", "value", "rounds", "note")


def _bomb_confusion(tables: Tables, name: str) -> pd.DataFrame:
    if tables.bomb is None:
        return pd.DataFrame(columns=["data"])
    matrix: pd.DataFrame = getattr(tables.bomb, name)
    return matrix.reset_index()


def _csv(path: Path, frame: pd.DataFrame) -> Path:
    return write_csv(path, frame)


def _records(frame: pd.DataFrame) -> JsonValue:
    return json_ready(frame.astype(object).where(frame.notna(), None).to_dict("records"))


def summary(evaluation: Evaluation, tables: Tables, info: RunInfo) -> JsonObject:
    """What was run and every aggregate, as one JSON-able dict."""
    settings = evaluation.settings
    outcome = tables.outcome
    return json_object(
        {
            "data": data_kind(evaluation),
            "command": info.command,
            "backend": info.backend,
            "machine": info.machine,
            "inputs": [str(p) for p in evaluation.inputs],
            "options": {
                "map": settings.map_name,
                "graph": settings.graph or "shipped",
                "combat": settings.combat,
                "bomb": settings.bomb,
                "models": str(settings.models),
                "mover": settings.mover,
                "seed": settings.seed,
                "implausible": settings.implausible,
                "deaths": settings.deaths if settings.combat else "data (no shooting)",
                "missing_fields": settings.missing,
                "sample": info.sample,
            },
            "mechanics": mechanics(evaluation.settings),
            "models": model_lines(evaluation.settings),
            "world": world_line(evaluation.settings),
            "line_of_sight_in": sight_line(evaluation.settings),
            "counts": run_counts(evaluation, tables),
            "wall_seconds": evaluation.wall_seconds,
            "compute_seconds": evaluation.compute_seconds,
            "trajectory": _records(tables.trajectory),
            "unevaluated": _records(tables.summary.unevaluated),
            "combat": _records(tables.combat),
            "death_counts": tables.deaths.counts,
            "outcome_winner_confusion": None
            if outcome is None
            else outcome.winner_confusion.to_dict(),
            "outcome_reason_confusion": None
            if outcome is None or outcome.end_reason_confusion is None
            else outcome.end_reason_confusion.to_dict(),
            "bomb": None
            if tables.bomb is None
            else {
                "rounds": tables.bomb.n_rounds,
                "rounds_with_anomalies": tables.bomb.anomalies,
                "metrics": _records(tables.bomb.table()),
                "plant_confusion": tables.bomb.plant_confusion.to_dict(),
                "defuse_confusion": tables.bomb.defuse_confusion.to_dict(),
            },
            "failures_by_kind": dict(Counter(f.kind for f in evaluation.failures)),
            "inferred_by_round": {
                f"{row.match}:{row.round}": row.inferred.split(WARNING_SEPARATOR)
                for row in tables.rounds.itertuples()
                if row.inferred
            },
            "cache_keys": dict(sorted(evaluation.cache_keys.items())),
        }
    )


# ---- the Markdown report ------------------------------------------------------------------------
