"""Where the jobs run: a local pool of worker processes, this process, or an existing Dask
cluster.

Both backends take a job function and its tasks and yield `(task, outcome)` as tasks finish,
where the outcome is the job's return value or a `RoundFailure` the backend made because the
worker died (its file and round are the runner's to fill in from the task). Use them as
context managers: leaving the block (normally, on Ctrl-C or on an error) cancels what has not
started and waits for what is running.

Local: a `ProcessPoolExecutor` whose workers are started by forkserver (spawn where there is
none), never by a plain fork: a worker process builds its own pybullet world on first use, so
no physics client is ever shared across a fork. Workers ignore Ctrl-C (the parent handles
it; with forkserver they never even receive it: `_start_forkserver`). At most one task per
worker is in flight, so when a worker dies (the pool then breaks and every in-flight task
with it) the suspects are those few tasks: each runs again alone in a fresh one-worker pool,
where a second death is that task's failure and the others complete; the rest of the batch
goes on in a new pool.

In this process (`--workers 0`): the jobs run one after another in the caller, with no process
to start (the quickest way to evaluate a few rounds); nothing isolates a crash, so a round that
brings the interpreter down ends the run (the rounds finished before it stay cached). A job
never raises, so the outcomes are the pool's.

Dask: the same job functions are submitted to a `dask.distributed` scheduler. The input files
must be readable by the workers at the same paths (a shared file system); results come back to
this process, which writes the outputs. A task whose workers keep dying (Dask's
`KilledWorker`) becomes a failure. Run workers with one thread each (`dask worker --nthreads 1`),
since the replay is CPU-bound Python.
"""

from __future__ import annotations

import multiprocessing
import signal
from collections import deque
from collections.abc import Callable, Generator, Iterable, Iterator
from concurrent.futures import FIRST_COMPLETED, Future, ProcessPoolExecutor, wait
from concurrent.futures.process import BrokenProcessPool
from typing import TypeVar

from decoy_cli.errors import DecoyError
from decoy_cli.esta import RoundFailure
from decoy_cli.esta.batch import INTERNAL_ERROR
from decoy_cli.evaluate.job import CRASH_MESSAGE, WORKER_CRASH

Task = TypeVar("Task")
Outcome = TypeVar("Outcome")
Outcomes = Iterator[tuple[Task, Outcome | RoundFailure]]
"""(task, what the job returned, or the failure that stands for it) as tasks finish."""


class _Broken:
    """The outcome of a task whose pool broke under it."""


_BROKEN = _Broken()


def _init_worker() -> None:
    """Worker initializer: Ctrl-C is the parent's to handle; pybullet is imported up front
    (without its banner, see `load_pybullet`)."""
    from decoy_cli.world.physics import load_pybullet

    signal.signal(signal.SIGINT, signal.SIG_IGN)
    load_pybullet()


def _context() -> multiprocessing.context.BaseContext:
    """forkserver (preloading the job module, so workers start fast) where available, else
    spawn; both start workers without a copy of the parent's threads or physics clients."""
    if "forkserver" in multiprocessing.get_all_start_methods():
        context = multiprocessing.get_context("forkserver")
        context.set_forkserver_preload(["decoy_cli.evaluate.job"])
        _start_forkserver()
        return context
    return multiprocessing.get_context("spawn")


def _start_forkserver() -> None:
    """Start the forkserver with SIGINT blocked: it and every worker it forks keep that signal
    mask, so a Ctrl-C, which a terminal sends to the whole process group, reaches only this
    process (a pending one arrives here when the mask is restored) and never stops a worker
    or the server while Python starts, which would print a traceback."""
    from multiprocessing import forkserver, resource_tracker

    resource_tracker.ensure_running()  # first: starting it unblocks SIGINT here
    held = signal.pthread_sigmask(signal.SIG_BLOCK, {signal.SIGINT})
    try:
        forkserver.ensure_running()
    finally:
        signal.pthread_sigmask(signal.SIG_SETMASK, held)


def _internal(error: BaseException) -> RoundFailure:
    return RoundFailure("", None, INTERNAL_ERROR, f"{type(error).__name__}: {error}")


def _crash() -> RoundFailure:
    return RoundFailure("", None, WORKER_CRASH, CRASH_MESSAGE)


class LocalBackend:
    """Jobs in `workers` local worker processes (see the module docstring)."""

    def __init__(self, workers: int) -> None:
        if workers < 1:
            raise DecoyError(f"--workers must be at least 1, not {workers}")
        self.workers = workers
        self._pool: ProcessPoolExecutor | None = None

    def __enter__(self) -> LocalBackend:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def close(self) -> None:
        """Cancel the tasks not started, wait for the running ones, stop the workers."""
        if self._pool is not None:
            self._pool.shutdown(wait=True, cancel_futures=True)
            self._pool = None

    def run(self, job: Callable[[Task], Outcome], tasks: Iterable[Task]) -> Outcomes[Task, Outcome]:
        """Yield (task, outcome) for every task, in the order they finish."""
        queue = deque(tasks)
        while queue:
            suspects = yield from self._run_pooled(job, queue)
            for task in suspects:
                yield task, self._run_alone(job, task)

    def _run_pooled(
        self, job: Callable[[Task], Outcome], queue: deque[Task]
    ) -> Generator[tuple[Task, Outcome | RoundFailure], None, list[Task]]:
        """Run the queue until it is empty or the pool breaks; returns the suspects."""
        if self._pool is None:
            self._pool = ProcessPoolExecutor(
                max_workers=self.workers, mp_context=_context(), initializer=_init_worker
            )
        inflight: dict[Future[Outcome], Task] = {}
        suspects: list[Task] = []
        while (queue or inflight) and not suspects:
            while queue and len(inflight) < self.workers:
                task = queue.popleft()
                try:
                    inflight[self._pool.submit(job, task)] = task
                except BrokenProcessPool:
                    queue.appendleft(task)
                    break
            if not inflight:  # broke before anything was in flight
                break
            done, _ = wait(inflight, return_when=FIRST_COMPLETED)
            for future in done:
                task = inflight.pop(future)
                outcome = _result(future)
                if isinstance(outcome, _Broken):
                    suspects.append(task)
                else:
                    yield task, outcome
        if suspects or (queue and not inflight):
            suspects.extend(inflight.values())  # their futures broke with the pool
            self._pool.shutdown(wait=True, cancel_futures=True)
            self._pool = None
        return suspects

    def _run_alone(self, job: Callable[[Task], Outcome], task: Task) -> Outcome | RoundFailure:
        """Run one task in a fresh one-worker pool; a dead worker is the task's failure."""
        pool = ProcessPoolExecutor(max_workers=1, mp_context=_context(), initializer=_init_worker)
        try:
            outcome = _result(pool.submit(job, task))
        finally:
            pool.shutdown(wait=True, cancel_futures=True)
        return _crash() if isinstance(outcome, _Broken) else outcome


def _result(future: Future[Outcome]) -> Outcome | RoundFailure | _Broken:
    try:
        return future.result()
    except BrokenProcessPool:
        return _BROKEN
    except Exception as error:  # e.g. a result that could not be sent back
        return _internal(error)


class InProcessBackend:
    """Jobs run one after another in this process (see the module docstring)."""

    def __enter__(self) -> InProcessBackend:
        return self

    def __exit__(self, *exc: object) -> None:
        pass

    def run(self, job: Callable[[Task], Outcome], tasks: Iterable[Task]) -> Outcomes[Task, Outcome]:
        """Yield (task, outcome) for every task, in order."""
        for task in tasks:
            yield task, job(task)


class DaskBackend:
    """Jobs on an existing dask.distributed cluster (see the module docstring)."""

    def __init__(self, address: str, timeout_s: float = 20.0) -> None:
        try:
            from distributed import Client
        except ImportError:
            raise DecoyError(
                "--scheduler needs dask.distributed: pip install 'decoy[dask]'"
            ) from None
        try:
            self.client = Client(address, timeout=f"{timeout_s}s", set_as_default=False)
        except (OSError, TimeoutError, ValueError) as error:
            raise DecoyError(
                f"cannot connect to the Dask scheduler at {address}: {error}"
            ) from None
        self.address = address
        self._futures: list[object] = []  # dask futures

    def __enter__(self) -> DaskBackend:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def close(self) -> None:
        """Cancel what is left of the last run and disconnect (the cluster keeps running)."""
        if self._futures:
            self.client.cancel(self._futures)
            self._futures = []
        self.client.close()

    def run(self, job: Callable[[Task], Outcome], tasks: Iterable[Task]) -> Outcomes[Task, Outcome]:
        """Yield (task, outcome) for every task, in the order they finish."""
        from distributed import KilledWorker, as_completed

        listed = list(tasks)
        if not listed:
            return
        futures = self.client.map(job, listed, pure=False)
        self._futures = list(futures)
        task_of = {future.key: task for future, task in zip(futures, listed, strict=True)}
        for future in as_completed(futures, loop=self.client.loop):
            outcome: Outcome | RoundFailure
            try:
                outcome = future.result()
            except KilledWorker:
                outcome = _crash()
            except Exception as error:
                outcome = _internal(error)
            task = task_of.pop(future.key)
            future.release()
            yield task, outcome
        self._futures = []
