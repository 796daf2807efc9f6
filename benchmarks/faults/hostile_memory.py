"""Peak memory of the commands on hostile match files built to exhaust memory (the
target: every case under 2 GB, with a clean error or a result).

    python benchmarks/faults/hostile_memory.py [--only NAME] [--keep FOLDER]

Writes each file into a temporary folder, then runs `decoy info FILE`, `decoy replay FILE:1
--models none` and `decoy evaluate FILE --no-combat --workers 1` on it, each in its own process
whose address space is capped at 4 GB (a runaway ends there instead of taking the machine), and
prints per case and command: the exit code, the last line of stderr, the wall time and the peak
resident memory of the process and its children. Cases: an xz bomb just over the size limit,
/dev/zero, a document of one million rounds, a round with 100,000 distinct players, a round of
200,000 frames, the largest round the limits let through, documents that only the `json`
fallback can read (a NaN) just under its own limit and just under the size limit, nesting a
million levels deep, and awpy 3 tables of the synthetic sample whose players' names are each
100,000 characters long in every tick row (awpy writes a name in every row; parquet stores it
once).
"""

from __future__ import annotations

import argparse
import json
import lzma
import os
import resource
import shutil
import subprocess
import tempfile
import time
from collections.abc import Callable, Iterator
from pathlib import Path

from decoy_cli.esta.source import LENIENT_MAX_MB, max_match_bytes

CAP_BYTES = 4 * 1024**3
TARGET_MB = 2048
PAGE = os.sysconf("SC_PAGE_SIZE")
HEAD = b'{"matchID": "hostile", "mapName": "de_dust2", "tickRate": 128, "gameRounds": ['


def _player(name: str, x: float) -> dict:
    return {
        "name": name,
        "steamID": None,
        "x": x,
        "y": 500.0,
        "z": 0.0,
        "hp": 100,
        "armor": 0,
        "isAlive": True,
        "activeWeapon": "Knife",
    }


def _frame(tick: int, players: list[dict]) -> dict:
    return {
        "tick": tick,
        "seconds": (tick - 1000) / 128,
        "t": {"players": players},
        "ct": {"players": []},
        "bomb": {"x": None, "y": None, "z": None},
        "bombPlanted": False,
    }


def _write_xz(path: Path, chunks: Iterator[bytes]) -> Path:
    compressor = lzma.LZMACompressor(preset=1)
    with path.open("wb") as handle:
        for chunk in chunks:
            handle.write(compressor.compress(chunk))
        handle.write(compressor.flush())
    return path


def _round_chunks(frames: Iterator[dict]) -> Iterator[bytes]:
    yield HEAD + b'{"roundNum": 1, "freezeTimeEndTick": 1000, "frames": ['
    first = True
    for frame in frames:
        yield (b"" if first else b",") + json.dumps(frame).encode()
        first = False
    yield b"]}]}"


def xz_bomb(folder: Path) -> Path:
    """Zeros in a list, just over the decompressed-size limit."""
    size = max_match_bytes() + (1 << 20)
    block = b"0," * (1 << 19)
    return _write_xz(
        folder / "xz_bomb.json.xz",
        iter([b"[", *[block] * (size // len(block) + 1), b"0]"]),
    )


def dev_zero(folder: Path) -> Path:
    return Path("/dev/zero")


def many_rounds(folder: Path) -> Path:
    """One million rounds without frames."""
    entry = b'{"roundNum": null, "frames": []}'
    chunks = [HEAD, entry, *[b"," + entry] * 999_999, b"]}"]
    return _write_xz(folder / "many_rounds.json.xz", iter(chunks))


def many_players(folder: Path) -> Path:
    """20,000 frames, each with 5 T players never seen before (100,000 distinct players)."""
    frames = (
        _frame(1000 + 2 * k, [_player(f"p{5 * k + j}", -500.0 + j) for j in range(5)])
        for k in range(20_000)
    )
    return _write_xz(folder / "many_players.json.xz", _round_chunks(frames))


def many_frames(folder: Path) -> Path:
    """200,000 frames of one player, all on the same few ticks apart (a 600 s round)."""
    frames = (_frame(1000 + k * 76_000 // 200_000, [_player("p", -500.0)]) for k in range(200_000))
    return _write_xz(folder / "many_frames.json.xz", _round_chunks(frames))


def widest_round(folder: Path) -> Path:
    """A large round the limits let through and the replay can play: 600 s of frames, one every
    3 ticks (distinct on the simulator's 60 Hz clock), each holding one of 64 players."""
    frames = (_frame(1000 + 3 * k, [_player(f"p{k % 64}", -500.0)]) for k in range(25_600))
    return _write_xz(folder / "widest_round.json.xz", _round_chunks(frames))


def _nan_document(path: Path, size: int) -> Path:
    """A document of about `size` bytes of JSON with a NaN, which only Python's json reads."""
    frame = json.dumps(_frame(1000, [_player("p", -500.0)])).encode()
    count = size // (len(frame) + 1)

    def chunks() -> Iterator[bytes]:
        yield HEAD + b'{"roundNum": 1, "bombPlantTick": NaN, "frames": ['
        yield frame
        for _ in range(count - 1):
            yield b"," + frame
        yield b"]}]}"

    return _write_xz(path, chunks())


def nan_fallback(folder: Path) -> Path:
    """A NaN in a document just under the size the json fallback reads."""
    return _nan_document(folder / "nan_fallback.json.xz", (LENIENT_MAX_MB - 1) * 1_000_000)


def nan_large(folder: Path) -> Path:
    """A NaN in a document just under the size limit (too large for the json fallback)."""
    return _nan_document(folder / "nan_large.json.xz", max_match_bytes() - (1 << 20))


def deep_nesting(folder: Path) -> Path:
    depth = 1_000_000
    return _write_xz(folder / "deep.json.xz", iter([HEAD, b"[" * depth, b"]" * depth, b"]}"]))


def awpy_long_names(folder: Path) -> Path:
    import pyarrow as pa
    import pyarrow.parquet as pq

    from decoy_cli.esta import read_match
    from decoy_cli.esta.awpy.writer import write_awpy3_folder
    from decoy_cli.synth.sample import SAMPLE_DIR

    tables = write_awpy3_folder(read_match(next(SAMPLE_DIR.glob("*.json.xz"))), folder / "awpy3")
    ticks = pq.read_table(tables / "snapshots.parquet")
    names = pa.array([n + "x" * 100_000 for n in ticks["name"].to_pylist()], pa.large_string())
    index = ticks.schema.get_field_index("name")
    pq.write_table(ticks.set_column(index, "name", names), tables / "snapshots.parquet")
    return tables


CASES: dict[str, Callable[[Path], Path]] = {
    "xz_bomb": xz_bomb,
    "dev_zero": dev_zero,
    "many_rounds": many_rounds,
    "many_players": many_players,
    "many_frames": many_frames,
    "widest_round": widest_round,
    "nan_fallback": nan_fallback,
    "nan_large": nan_large,
    "deep_nesting": deep_nesting,
    "awpy_long_names": awpy_long_names,
}


def _tree_rss_bytes(root: int) -> int:
    """Resident memory of `root` and every process descending from it (from /proc)."""
    parent: dict[int, int] = {}
    for entry in Path("/proc").iterdir():
        if entry.name.isdigit():
            try:
                stat = (entry / "stat").read_text()
            except OSError:
                continue
            parent[int(entry.name)] = int(stat[stat.rindex(")") + 2 :].split()[1])
    tree, total = {root}, 0
    changed = True  # a child's pid may be lower than its parent's: grow the tree to a fixpoint
    while changed:
        changed = False
        for pid, ppid in parent.items():
            if ppid in tree and pid not in tree:
                tree.add(pid)
                changed = True
    for pid in tree:
        try:
            total += int((Path("/proc") / str(pid) / "statm").read_text().split()[1]) * PAGE
        except (OSError, IndexError, ValueError):
            continue
    return total


def measure(command: list[str], out: Path) -> tuple[int, str, float, float]:
    """(exit code, last stderr line, seconds, peak MB) of a command: the peak of the summed
    resident memory of its process tree (worker processes included), sampled every 20 ms, and
    never below the peak the kernel reports for the process (and the children it waited for)."""
    cap = (CAP_BYTES, CAP_BYTES)
    started = time.perf_counter()
    with tempfile.TemporaryFile() as stderr:
        process = subprocess.Popen(
            command,
            cwd=out,
            stdout=subprocess.DEVNULL,
            stderr=stderr,
            preexec_fn=lambda: resource.setrlimit(resource.RLIMIT_AS, cap),
        )
        peak, own, code = 0, 0, None
        while code is None:
            pid, status, usage = os.wait4(process.pid, os.WNOHANG)
            if pid:
                own, code = usage.ru_maxrss * 1024, os.waitstatus_to_exitcode(status)
            else:
                peak = max(peak, _tree_rss_bytes(process.pid))
                time.sleep(0.02)
        process.returncode = code
        seconds = time.perf_counter() - started
        peak = max(peak, own)
        stderr.seek(0)
        lines = stderr.read().decode(errors="replace").strip().splitlines() or [""]
    return code, lines[-1][:160], seconds, peak / 1024**2


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--only", choices=sorted(CASES), action="append")
    parser.add_argument("--keep", type=Path, help="Write the files here and keep them.")
    args = parser.parse_args()
    folder = args.keep or Path(tempfile.mkdtemp(prefix="decoy-hostile-"))
    folder.mkdir(parents=True, exist_ok=True)
    decoy = shutil.which("decoy") or "decoy"
    worst = 0.0
    print(f"cap {CAP_BYTES / 1024**3:.0f} GB per process; target < {TARGET_MB} MB")
    print("case\tcommand\texit\tseconds\tpeak MB\tlast stderr line")
    try:
        for name in args.only or list(CASES):
            file = CASES[name](folder)
            commands = (
                ["info", str(file)],
                ["replay", f"{file}:1", "--models", "none"],
                ["evaluate", str(file), "--no-combat", "--workers", "1", "--out", f"out-{name}"],
            )
            for command in commands:
                code, last, seconds, peak = measure([decoy, *command], folder)
                worst = max(worst, peak)
                print(f"{name}\t{command[0]}\t{code}\t{seconds:.1f}\t{peak:.0f}\t{last}")
    finally:
        if args.keep is None:
            shutil.rmtree(folder, ignore_errors=True)
    verdict = "within" if worst < TARGET_MB else "OVER"
    print(f"largest peak {worst:.0f} MB: {verdict} the {TARGET_MB} MB target")


if __name__ == "__main__":
    main()
