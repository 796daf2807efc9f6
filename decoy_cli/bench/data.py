"""Throughput on match files: the ESTA reader, and the replay of whole rounds.

The files are, in order of preference: a folder the user names, the real T-side rounds in
`../shared/data/esta_dust2_tside` next to the project (a development checkout), or the
synthetic sample shipped in `examples/sample/`. Without any of them these sections are skipped,
and the report says why.
"""

from __future__ import annotations

import statistics
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from decoy_cli.bench.records import DataRecord, ReaderResult, ReplayResult
from decoy_cli.errors import DecoyError, EstaError
from decoy_cli.esta import (
    Round,
    RoundFailure,
    each_round,
    iter_match_files,
    iter_rounds,
    read_match,
)
from decoy_cli.esta.source import read_bytes
from decoy_cli.metrics import player_metrics
from decoy_cli.replay.replayer import ReplayOptions, replay_round
from decoy_cli.sim.combat import DamageModel
from decoy_cli.synth.sample import SAMPLE_DIR
from decoy_cli.waypoints.build import builtin_graph
from decoy_cli.world.navmesh import nav_world
from decoy_cli.world.physics import PhysicsWorld

PROJECT_ROOT = Path(__file__).resolve().parents[2]
REAL_DATA = PROJECT_ROOT.parent / "shared" / "data" / "esta_dust2_tside"
"""The real T-side ESTA rounds of a development checkout (never part of the project)."""

DATA_CANDIDATES = (("real", REAL_DATA), ("synthetic sample", SAMPLE_DIR))

MAX_FAILURES_KEPT = 5


@dataclass(frozen=True)
class BenchData:
    """Match files to measure on and where they came from ("given", "real" or the sample)."""

    kind: str
    folder: Path
    files: list[Path]

    def describe(self) -> DataRecord:
        return {"kind": self.kind, "folder": str(self.folder), "files": len(self.files)}


def find_data(
    given: Path | None = None, candidates: tuple[tuple[str, Path], ...] = DATA_CANDIDATES
) -> BenchData | None:
    """The folder the user gave (must hold match files), else the first candidate that does."""
    if given is not None:
        return BenchData("given", given, iter_match_files(given))
    for kind, folder in candidates:
        if not folder.is_dir():
            continue
        try:
            return BenchData(kind, folder, iter_match_files(folder))
        except EstaError:
            continue
    return None


def reader_throughput(files: list[Path], repeats: int = 1) -> ReaderResult:
    """`read_match` per file (median of `repeats`): seconds per file and MB per second.

    MB are 10^6 bytes of the file on disk (compressed) and of the JSON it holds (decompressed).
    """
    seconds: list[float] = []
    compressed = decompressed = rounds = 0
    failures: list[str] = []
    for path in files:
        try:
            size = len(read_bytes(path))
            times = []
            for _ in range(max(repeats, 1)):
                started = time.perf_counter()
                match = read_match(path)
                times.append(time.perf_counter() - started)
        except EstaError as error:
            failures.append(str(error))
            continue
        seconds.append(statistics.median(times))
        compressed += path.stat().st_size
        decompressed += size
        rounds += len(match.rounds)
    total = sum(seconds)
    result: ReaderResult = {
        "files": len(seconds),
        "failed": len(failures),
        "failures": failures[:MAX_FAILURES_KEPT],
        "repeats": repeats,
    }
    if not seconds:
        return result
    return result | {
        "rounds": rounds,
        "compressed_mb": compressed / 1e6,
        "decompressed_mb": decompressed / 1e6,
        "seconds": total,
        "s_per_file_median": statistics.median(seconds),
        "s_per_file_min": min(seconds),
        "s_per_file_max": max(seconds),
        "mb_per_s_decompressed": decompressed / 1e6 / total,
        "mb_per_s_compressed": compressed / 1e6 / total,
        "rounds_per_s": rounds / total,
    }


def replay_throughput(
    files: list[Path],
    max_rounds: int | None = None,
    model: DamageModel | None = None,
    *,
    combat: bool = True,
    bomb: bool = True,
    seed: int = 0,
) -> ReplayResult:
    """Rounds per second of snap + plan + replay + metrics in one process, on one world.

    The replay runs as `decoy replay` does by default (kinematic mover, bomb on, combat on
    when there is a damage model); reading the files is not timed (see `reader_throughput`).
    One round is replayed first, untimed, to load the compiled kernels. A file or round that
    cannot be replayed is counted as a failure with its message.
    """
    options = ReplayOptions(
        combat=combat and model is not None,
        bomb=bomb,
        mover="kinematic",
        damage_model=model,
        seed=seed,
    )
    graph = builtin_graph()
    per_round: list[float] = []
    frames = 0
    game_s = 0.0
    failures: list[RoundFailure] = []
    wall = cpu = 0.0
    warmed = False
    with PhysicsWorld(nav_world()) as physics:

        def timed(round_: Round) -> tuple[float, float]:
            """The wall and CPU seconds of the replay and its metrics."""
            started, cpu_started = time.perf_counter(), time.process_time()
            player_metrics(round_, replay_round(round_, graph, options, physics=physics).trace())
            return time.perf_counter() - started, time.process_time() - cpu_started

        rounds = each_round(iter_rounds(files), timed, "replay error", catch=DecoyError)
        for item in rounds if max_rounds is None or max_rounds > 0 else ():
            if isinstance(item, RoundFailure):
                failures.append(item)
                continue
            if not warmed:
                warmed = True
                continue
            round_, (round_wall, round_cpu) = item
            per_round.append(round_wall)
            wall += round_wall
            cpu += round_cpu
            frames += round_.num_frames
            game_s += float(np.ptp(round_.frame_seconds))
            if max_rounds is not None and len(per_round) >= max_rounds:
                break  # before the next round is replayed
    result: ReplayResult = {
        "rounds": len(per_round),
        "failed": len(failures),
        "failures": [f"{f.where}: {f.message}" for f in failures[:MAX_FAILURES_KEPT]],
        "options": {
            "combat": options.combat,
            "bomb": options.bomb,
            "mover": options.mover,
            "seed": seed,
        },
    }
    if not per_round:
        return result
    return result | {
        "frames": frames,
        "wall_s": wall,
        "cpu_s": cpu,
        "game_s": game_s,
        "rounds_per_s": len(per_round) / wall,
        "rounds_per_cpu_s": len(per_round) / cpu if cpu > 0 else None,
        "s_per_round_median": statistics.median(per_round),
        "time_scale": game_s / wall,
    }
