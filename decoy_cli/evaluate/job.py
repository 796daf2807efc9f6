"""The per-file and per-round jobs that worker processes run, and what they return.

A job is a plain function of a small picklable task, so the same job runs in a local process
pool and on a Dask cluster. Each worker process (each thread, on a multi-threaded Dask worker)
builds its waypoint graph, pybullet world and damage model once, on first use, and keeps the
last match files it read, so the rounds of one file read it once per worker. A job never raises:
a bad file, a broken round or a bug becomes a `RoundFailure` with a one-line reason
(`decoy_cli.esta.failure_from`), so the batch goes on.

A round's result is a `RoundRecord` (decoy_cli/evaluate/record.py).
"""

from __future__ import annotations

import json
import signal
import threading
import time
from collections import OrderedDict
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

import msgspec

from decoy_cli.damage.choice import ModelChoice
from decoy_cli.errors import DecoyError
from decoy_cli.esta import Match, Round, RoundFailure, failure_from, read_match
from decoy_cli.esta.batch import UNREADABLE_FILE
from decoy_cli.esta.content import content_sha256
from decoy_cli.esta.plausibility import Implausible
from decoy_cli.evaluate.record import RoundRecord, build_record
from decoy_cli.evaluate.settings import EvalSettings, round_seed, seed_source
from decoy_cli.files import JsonValue
from decoy_cli.waypoints.graph import WaypointGraph
from decoy_cli.waypoints.places import PlaceFinder
from decoy_cli.world.occlusion import OcclusionScene, read_sight_scene

if TYPE_CHECKING:
    from decoy_cli.replay.replayer import ReplayResult
    from decoy_cli.sim.combat import DamageModel

WORKER_CRASH = "worker crash"
REPLAY_ERROR = "replay error"
TIMEOUT = "timeout"
CRASH_MESSAGE = (
    "the worker process died while evaluating this (a crash, a kill or running out of memory)"
)

_MATCHES_KEPT = 2
"""Match files a worker keeps in memory (the rounds of a file mostly arrive together)."""


@dataclass(frozen=True)
class IndexTask:
    """Read one match file and list its rounds."""

    file: str
    file_sha: str
    settings: EvalSettings


@dataclass(frozen=True)
class RoundTask:
    """Replay one round of a match file and measure it."""

    file: str
    file_sha: str
    round_num: int
    key: str
    settings: EvalSettings
    timeout_s: float | None = None
    """Wall-clock seconds the round may take (None: no limit); not part of the cache key."""


class FileIndex(msgspec.Struct, frozen=True):
    """A match file's identity, map, provenance and round numbers (built and broken)."""

    file_sha: str
    match_id: str
    map_name: str
    synthetic: bool
    provenance: str
    """The top-level `provenance` value as JSON ("" when the file has none)."""
    rounds: list[int]
    round_errors: dict[int, str]


class _WorkerState:
    """One worker's graph, physics world, damage models and recently read matches."""

    def __init__(self, settings: EvalSettings) -> None:
        from decoy_cli.waypoints.build import graph_world
        from decoy_cli.world.physics import PhysicsWorld

        self.key = worker_key(settings)
        self.graph = run_graph(settings)
        self.places = PlaceFinder(self.graph)
        self.physics = PhysicsWorld(graph_world(self.graph))
        self.sight = run_sight(settings, self.graph)
        self.models: dict[ModelChoice, DamageModel | None] = {}
        self.matches: OrderedDict[tuple[str, str, str, float | None], Match] = OrderedDict()

    def damage_model(self, choice: ModelChoice) -> DamageModel | None:
        """The damage model of a `--models` choice, loaded once (torch on one thread)."""
        if choice not in self.models:
            from decoy_cli.damage import load_damage_model

            model = load_damage_model(choice)
            if model is not None:
                import torch

                torch.set_num_threads(1)  # parallelism comes from the worker processes
            self.models[choice] = model
        return self.models[choice]

    def match(
        self, file: str, file_sha: str, implausible: Implausible, rate: float | None
    ) -> Match:
        """The match read from `file` under the run's policy for implausible rounds and at its
        frame rate, checked to be the content the run hashed."""
        key = (file, file_sha, implausible, rate)
        if key in self.matches:
            self.matches.move_to_end(key)
            return self.matches[key]
        path = Path(file)
        if content_sha256(path) != file_sha:
            raise DecoyError(f"{file}: the file changed while the evaluation ran")
        match = read_match(path, implausible=implausible, rate=rate)
        self.matches[key] = match
        while len(self.matches) > _MATCHES_KEPT:
            self.matches.popitem(last=False)
        return match


_local = threading.local()


def run_graph(settings: EvalSettings) -> WaypointGraph:
    """The waypoint graph a run replays on: the user's `--graph` (checked to be the file the
    run hashed), else the map's shipped one."""
    from decoy_cli.waypoints.build import builtin_graph

    if not settings.graph:
        return builtin_graph(settings.map_name, settings.shipped_world)
    if content_sha256(Path(settings.graph)) != settings.graph_sha:
        raise DecoyError(f"{settings.graph}: the graph file changed while the evaluation ran")
    return WaypointGraph.load(settings.graph)


def run_sight(settings: EvalSettings, graph: WaypointGraph) -> OcclusionScene | None:
    """The geometry a run tests line of sight in: the user's `--sight-mesh` (checked to be the
    file the run hashed), else None (the graph's world)."""
    if not settings.sight_mesh:
        return None
    scene = read_sight_scene(Path(settings.sight_mesh), graph.positions, settings.map_name)
    if scene.sha256 != settings.sight_mesh_sha:
        raise DecoyError(f"{settings.sight_mesh}: the mesh changed while the evaluation ran")
    return scene


def worker_key(settings: EvalSettings) -> tuple[str, ...]:
    """What a worker's state is built from: the map, the graph and the sight mesh."""
    return (settings.map_name, settings.graph, settings.graph_sha, settings.sight_mesh_sha)


def worker_state(settings: EvalSettings) -> _WorkerState:
    """This thread's worker state, built on first use (one per process in a local pool)."""
    state = getattr(_local, "state", None)
    if state is None or state.key != worker_key(settings):
        state = _WorkerState(settings)
        _local.state = state
    return state


def is_synthetic(match_id: str, provenance: JsonValue) -> bool:
    """Whether a match says it was generated, not recorded (matchID or provenance)."""
    text = f"{match_id} {json.dumps(provenance, default=str)}".lower()
    return "synthetic" in text


def index_file(task: IndexTask) -> FileIndex | RoundFailure:
    """Read a match file and list its rounds; the worker keeps the match for its rounds."""
    try:
        match = worker_state(task.settings).match(
            task.file, task.file_sha, task.settings.implausible, task.settings.rate
        )
    except Exception as error:
        return failure_from(error, task.file, None, UNREADABLE_FILE)
    provenance = match.meta.get("provenance")
    return FileIndex(
        file_sha=task.file_sha,
        match_id=match.match_id,
        map_name=match.map_name,
        synthetic=is_synthetic(match.match_id, provenance),
        provenance="" if provenance is None else json.dumps(provenance, sort_keys=True),
        rounds=[r.round_num for r in match.rounds],
        round_errors={num: str(error) for num, error in match.round_errors.items()},
    )


class RoundTimeout(DecoyError):
    """A round that took longer than its task's time limit."""


@contextmanager
def time_limit(seconds: float | None) -> Iterator[None]:
    """Raise RoundTimeout in this block after `seconds` of wall-clock time. Only a process's
    main thread can be interrupted (a local worker process is one); elsewhere, such as on a
    multi-threaded Dask worker, the block runs without a limit."""
    if seconds is None or threading.current_thread() is not threading.main_thread():
        yield
        return

    def expire(signum: int, frame: object) -> None:
        raise RoundTimeout(f"the round took longer than its time limit of {seconds:g} s")

    previous = signal.signal(signal.SIGALRM, expire)
    signal.setitimer(signal.ITIMER_REAL, seconds)
    try:
        yield
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
        signal.signal(signal.SIGALRM, previous)


def evaluate_round(task: RoundTask) -> RoundRecord | RoundFailure:
    """Replay one round with the task's settings and measure it (never raises); a round over
    the task's time limit is a TIMEOUT failure."""
    try:
        with time_limit(task.timeout_s):
            return _evaluate(task)
    except RoundTimeout as error:
        return RoundFailure(task.file, task.round_num, TIMEOUT, str(error))
    except Exception as error:
        return failure_from(error, task.file, task.round_num, REPLAY_ERROR)


def _evaluate(task: RoundTask) -> RoundRecord:
    state = worker_state(task.settings)
    round_ = state.match(
        task.file, task.file_sha, task.settings.implausible, task.settings.rate
    ).round(task.round_num)
    settings = task.settings
    model = state.damage_model(settings.models) if settings.combat else None
    started = time.perf_counter()
    result = _replay(state, round_, settings, model, task)
    return build_record(task, round_, result, state.places, time.perf_counter() - started)


def _replay(
    state: _WorkerState,
    round_: Round,
    settings: EvalSettings,
    model: DamageModel | None,
    task: RoundTask,
) -> ReplayResult:
    from decoy_cli.replay.replayer import ReplayOptions, replay_round

    seed = round_seed(settings, seed_source(round_, task.file_sha), task.round_num)
    options = ReplayOptions.of(settings, model, seed=seed, sight=state.sight)
    return replay_round(round_, state.graph, options, physics=state.physics)
