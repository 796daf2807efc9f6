"""Run an evaluation: find the match files, index them, run every round, collect the results.

The steps, all resumable:

1. The inputs (files and folders) become match files (`decoy_cli.esta.collect_match_files`); files
   in a folder without a match-file suffix are listed as ignored. Each file is hashed (SHA-256
   of its bytes): the hash keys the cache, and the same content given twice is evaluated once.
2. Each file's index (match ID, map, provenance, round numbers, rounds the reader rejected) is
   read from the cache or computed by a worker (`index_file`) and cached.
3. Files of another map are skipped, with the reason, as a failure of the file; rounds the reader
   rejected are failures of their round. With `sample`, a seeded random sample of the rounds
   (ordered by file content and round number, so it does not depend on paths) is kept.
4. Every round already in the cache is loaded; the others run in the backend's workers
   (`evaluate_round`). Each result is cached atomically as it arrives, so an interrupt keeps
   every finished round; a failure is recorded with its reason and the batch goes on.

Nothing here prints: progress is reported through a callback, the result is returned.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Protocol

import numpy as np

from decoy_cli.damage.choice import ModelChoice, ModelFolder, ModelName
from decoy_cli.errors import DecoyError, EstaError, GraphError
from decoy_cli.esta import RoundFailure, collect_match_files
from decoy_cli.esta.batch import BROKEN_ROUND, INTERNAL_ERROR, UNREADABLE_FILE, map_failure
from decoy_cli.esta.content import content_sha256
from decoy_cli.esta.plausibility import Implausible
from decoy_cli.evaluate.backends import Outcome, Outcomes, Task
from decoy_cli.evaluate.cache import RunCache
from decoy_cli.evaluate.heat import HeatGrid
from decoy_cli.evaluate.job import (
    FileIndex,
    IndexTask,
    RoundTask,
    evaluate_round,
    index_file,
    run_graph,
)
from decoy_cli.evaluate.record import RoundRecord
from decoy_cli.evaluate.settings import (
    EvalSettings,
    code_fingerprint,
    folder_fingerprint,
    index_key,
    round_key,
)
from decoy_cli.evaluate.tables import Accumulator
from decoy_cli.replay.deaths import DeathProtocol
from decoy_cli.replay.missing import Missing
from decoy_cli.sim.setup import SIGHT_WITHOUT_SHOOTING, MoverName
from decoy_cli.waypoints.build import GameWorld
from decoy_cli.waypoints.graph import WaypointGraph
from decoy_cli.waypoints.places import place_names
from decoy_cli.world.occlusion import read_sight_scene


class Backend(Protocol):
    """Runs a job over tasks and yields (task, outcome) as they finish (see backends.py)."""

    def run(
        self, job: Callable[[Task], Outcome], tasks: Sequence[Task]
    ) -> Outcomes[Task, Outcome]: ...


@dataclass(frozen=True)
class ProgressEvent:
    """Where a run stands: `stage` is "index" (files) or "rounds"."""

    stage: str
    done: int
    total: int
    failed: int


@dataclass(frozen=True)
class MatchFile:
    """One input file and, once indexed, what it holds."""

    path: Path
    sha: str
    index: FileIndex | None = None


@dataclass
class Evaluation:
    """What a run did and produced: the accumulated results, failures and counts."""

    settings: EvalSettings
    inputs: list[Path]
    files: list[MatchFile]
    ignored: list[Path]
    """Files in the input folders without a match-file suffix (not read)."""
    duplicates: list[tuple[Path, Path]]
    """(file, the earlier file with the same content): evaluated once."""
    accumulator: Accumulator
    failures: list[RoundFailure] = field(default_factory=list)
    rounds_planned: int = 0
    rounds_available: int = 0
    """Rounds of the map in the input before sampling (built or broken)."""
    computed: int = 0
    cached: int = 0
    compute_seconds: float = 0.0
    wall_seconds: float = 0.0
    cache_keys: dict[str, str] = field(default_factory=dict)
    """The cache key of each round evaluated, by "file_sha:round" (`round_id`)."""


def round_id(file_sha: str, round_num: int) -> str:
    """A round of a run: its file's content hash and its number ("sha:round")."""
    return f"{file_sha}:{round_num}"


def make_settings(
    *,
    map_name: str,
    combat: bool,
    bomb: bool,
    models: ModelChoice,
    mover: MoverName,
    seed: int,
    implausible: Implausible = "fail",
    rate: float | None = None,
    deaths: DeathProtocol = "simulated",
    missing: Missing = "infer",
    fastdtw: bool | None = None,
    graph: Path | None = None,
    sight_mesh: Path | None = None,
    world: GameWorld = "csgo",
) -> EvalSettings:
    """Settings for a run; with combat the damage model is loaded once here, so a bad
    `--models` choice fails at once with one line instead of in every round. `fastdtw` None
    means: on for the paper's Table 2 setting (no combat, no bomb), off otherwise. The world:
    the graph's, else the shipped one `world` names."""
    from decoy_cli.waypoints.build import builtin_graph, canonical_map

    name = canonical_map(map_name)
    graph_path, graph_sha = "", ""
    graph_of_run = None
    if graph is not None and world != "csgo":
        raise DecoyError("--graph brings its own world: leave out --world")
    world_of_run = "" if graph is not None else world
    if world_of_run == "cs2":
        graph_of_run = builtin_graph(name, "cs2")  # fails now when none ships
    if graph is not None:  # absolute, for workers elsewhere; its map must be the run's
        graph_path = str(graph.expanduser().resolve())
        graph_sha = content_sha256(Path(graph_path))
        graph_of_run = WaypointGraph.load(graph_path)
        graph_map = str(graph_of_run.meta.get("map", ""))
        if graph_map != name:
            raise GraphError(f"{graph}: a graph of {graph_map or 'no map'}, not {name} (--map)")
    models_fingerprint = ""
    if combat:
        from decoy_cli.damage import SHIPPED_CHOICES, load_damage_model, resolve_models

        if models not in (*SHIPPED_CHOICES, ModelName.NONE):  # absolute, for workers elsewhere
            models = ModelFolder(str(resolve_models(models).resolve()))
        if load_damage_model(models) is not None:
            models_fingerprint = folder_fingerprint(resolve_models(models))
    sight_path, sight_sha = "", ""
    if sight_mesh is not None:  # checked here: a wrong mesh fails once, at once
        if not models_fingerprint:
            raise DecoyError(SIGHT_WITHOUT_SHOOTING)
        sight_path = str(sight_mesh.expanduser().resolve())
        feet = (graph_of_run or builtin_graph(name)).positions
        sight_sha = read_sight_scene(Path(sight_path), feet, name).sha256
    return EvalSettings(
        map_name=name,
        combat=combat,
        bomb=bomb,
        models=models if combat else ModelName.NONE,
        mover=mover,
        seed=seed,
        grid=HeatGrid.for_map(name),
        code=code_fingerprint(name),
        models_fingerprint=models_fingerprint,
        implausible=implausible,
        rate=rate,
        deaths=deaths,
        missing=missing,
        fastdtw=(not combat and not bomb) if fastdtw is None else fastdtw,
        world=world_of_run,
        graph=graph_path,
        graph_sha=graph_sha,
        sight_mesh=sight_path,
        sight_mesh_sha=sight_sha,
    )


DEFAULT_ROUND_TIMEOUT_S = 300.0
"""Default wall-clock limit of one round in `decoy evaluate`: hundreds of times what a real round
takes to replay, so only a broken or hostile round reaches it."""


def default_inputs() -> list[Path]:
    """The inputs of a run given none: the shipped synthetic sample (an error without it)."""
    from decoy_cli.synth.sample import SAMPLE_DIR

    if not SAMPLE_DIR.is_dir() or not any(SAMPLE_DIR.glob("*.json*")):
        raise DecoyError(
            f"no input given and no shipped sample in {SAMPLE_DIR}: pass ESTA match files "
            "or folders (or generate the sample with `decoy make-sample`)"
        )
    return [SAMPLE_DIR]


def run_evaluation(
    inputs: Sequence[Path],
    settings: EvalSettings,
    out: Path,
    backend: Backend,
    *,
    sample: int | None = None,
    on_progress: Callable[[ProgressEvent], None] | None = None,
    job: Callable[[RoundTask], RoundRecord | RoundFailure] = evaluate_round,
    round_timeout_s: float | None = None,
) -> Evaluation:
    """Evaluate every round (or a sample) of the inputs; see the module docstring.

    `round_timeout_s` limits the wall-clock time of each round (a round over it is a recorded
    "timeout" failure; None: no limit).

    `job` is the per-round function the workers run (a test can wrap it to inject a crash).
    An OutputError while caching (a full disk) stops the run; what was cached stays.
    """
    started = time.perf_counter()
    paths, ignored = collect_match_files(inputs)
    cache = RunCache(out)
    evaluation = Evaluation(
        settings=settings,
        inputs=list(inputs),
        files=[],
        ignored=ignored,
        duplicates=[],
        accumulator=Accumulator(settings, place_names(run_graph(settings))),
    )
    failures = evaluation.failures
    by_sha: dict[str, Path] = {}
    for path in paths:
        try:
            sha = content_sha256(path)
        except EstaError as error:
            failures.append(RoundFailure(str(path), None, UNREADABLE_FILE, str(error)))
            continue
        if sha in by_sha:
            evaluation.duplicates.append((path, by_sha[sha]))
            continue
        by_sha[sha] = path
        evaluation.files.append(MatchFile(path, sha))

    evaluation.files = _index(evaluation.files, settings, cache, backend, failures, on_progress)
    tasks = _round_tasks(evaluation, sample, round_timeout_s)
    evaluation.rounds_planned = len(tasks)
    pending: list[RoundTask] = []
    for task in tasks:
        record = cache.load_round(task.key)
        if record is None:
            pending.append(task)
        else:
            evaluation.accumulator.add(record, task.file)
            evaluation.cache_keys[round_id(task.file_sha, task.round_num)] = task.key
            evaluation.cached += 1

    compute_started = time.perf_counter()
    failed = 0
    _report(on_progress, "rounds", 0, len(pending), 0)
    for done, (task, outcome) in enumerate(backend.run(job, pending), start=1):
        if isinstance(outcome, RoundRecord):
            cache.store_round(outcome)
            evaluation.accumulator.add(outcome, task.file)
            evaluation.cache_keys[round_id(task.file_sha, task.round_num)] = task.key
            evaluation.computed += 1
        else:
            failed += 1
            failures.append(_round_failure(task, outcome))
        _report(on_progress, "rounds", done, len(pending), failed)
    evaluation.compute_seconds = time.perf_counter() - compute_started
    evaluation.wall_seconds = time.perf_counter() - started
    failures.sort(key=lambda f: (f.file, -1 if f.round_num is None else f.round_num))
    return evaluation


def _report(
    on_progress: Callable[[ProgressEvent], None] | None,
    stage: str,
    done: int,
    total: int,
    failed: int,
) -> None:
    if on_progress is not None:
        on_progress(ProgressEvent(stage, done, total, failed))


def _round_failure(task: RoundTask, outcome: object) -> RoundFailure:
    """The failure of a round task, with the task's file and round (a backend's crash report
    does not know them)."""
    if isinstance(outcome, RoundFailure):
        return replace(outcome, file=task.file, round_num=task.round_num)
    return RoundFailure(task.file, task.round_num, INTERNAL_ERROR, f"unexpected result {outcome!r}")


def _index(
    files: list[MatchFile],
    settings: EvalSettings,
    cache: RunCache,
    backend: Backend,
    failures: list[RoundFailure],
    on_progress: Callable[[ProgressEvent], None] | None,
) -> list[MatchFile]:
    """Every file with its index (cached or computed); unreadable files become failures."""
    indexes: dict[str, FileIndex] = {}
    pending: list[IndexTask] = []
    for file in files:
        found = cache.load_index(index_key(settings, file.sha), file.sha)
        if found is None:
            pending.append(IndexTask(str(file.path), file.sha, settings))
        else:
            indexes[file.sha] = found
    failed = 0
    _report(on_progress, "index", 0, len(pending), 0)
    for done, (task, outcome) in enumerate(backend.run(index_file, pending), start=1):
        if isinstance(outcome, FileIndex):
            cache.store_index(index_key(settings, task.file_sha), outcome)
            indexes[task.file_sha] = outcome
        else:
            failed += 1
            failures.append(RoundFailure(task.file, None, outcome.kind, outcome.message))
        _report(on_progress, "index", done, len(pending), failed)
    return [MatchFile(f.path, f.sha, indexes.get(f.sha)) for f in files]


def _round_tasks(
    evaluation: Evaluation, sample: int | None, timeout_s: float | None
) -> list[RoundTask]:
    """The rounds to evaluate; other maps and rejected rounds go to the failures."""
    settings = evaluation.settings
    population: list[tuple[str, int, MatchFile, str | None]] = []
    for file, index in ((f, f.index) for f in evaluation.files if f.index is not None):
        count = len(index.rounds) + len(index.round_errors)
        other = map_failure(file.path, index.map_name, count, settings.map_name)
        if other is not None:
            evaluation.failures.append(other)
            continue
        population.extend((file.sha, num, file, None) for num in index.rounds)
        population.extend((file.sha, num, file, msg) for num, msg in index.round_errors.items())
    population.sort(key=lambda item: (item[0], item[1]))
    evaluation.rounds_available = len(population)
    if sample is not None and sample < len(population):
        rng = np.random.default_rng(settings.seed)
        chosen = np.sort(rng.choice(len(population), size=sample, replace=False))
        population = [population[i] for i in chosen]
    order = {file.sha: i for i, file in enumerate(evaluation.files)}
    population.sort(key=lambda item: (order[item[0]], item[1]))
    tasks = []
    for sha, num, file, error in population:
        if error is not None:
            evaluation.failures.append(RoundFailure(str(file.path), num, BROKEN_ROUND, error))
        else:
            key = round_key(settings, sha, num)
            tasks.append(RoundTask(str(file.path), sha, num, key, settings, timeout_s))
    return tasks
