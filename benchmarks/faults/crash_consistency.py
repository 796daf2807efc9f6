"""Crash consistency of `decoy evaluate` under fault injection: what a SIGKILL, a
Ctrl-C, a full disk, a read-only folder or a second run leaves behind, and whether a rerun gives
the outputs of a run never interrupted.

    python benchmarks/faults/crash_consistency.py [--kills 50] [--interrupts 10] [--seed 0]
        [--from-lock] [--only kills,interrupts,lock,disk,downloads] [--keep FOLDER]

The run under test is `decoy evaluate` on 4 sampled rounds of the shipped synthetic sample
(`--no-combat`, bomb on, 2 workers), each time in a fresh folder with `--out out`. First one
uninterrupted run gives the reference outputs and its wall time T. Then:

* kills: the run is killed with SIGKILL at a random moment of the i-th of N equal slices of
  [0, 1.05 T] (with `--from-lock`, of the time H it holds its folder, counted from the moment
  it takes the lock: what Python's start-up leaves out; a kill that comes after the run ended
  is not counted, and another is drawn);
  what it left is checked (every cache entry decodes and holds its own key), then the same
  command runs again to the end, and its outputs must equal the reference's, with every round
  once in the cache and no temporary file or staging folder left;
* interrupts: Ctrl-C (SIGINT to the process group) at a random moment once the run holds its
  folder: one "interrupted ... run the same command again to resume" line (or, once the
  outputs are written, an exit by the signal), no traceback, then a rerun equal to the
  reference;
* lock: a second run into a folder a live run holds is refused in one `error:` line (and the
  live run ends as the reference); a run killed with SIGKILL leaves a lock the next run takes
  over; a lock file naming a live process that is not a decoy run does not stop a run;
* disk (needs `mount`, so root): a run into a 200 kB tmpfs, the same run and a run with
  another seed into a tmpfs nearly filled after a good run, and a run into that folder
  remounted read-only each end in one `error:` line, and the good run's outputs are still
  there, byte for byte;
* downloads: `decoy download` (a match of the sample, served by a local HTTP server) and
  `decoy models download-decoy` (the paper's checkpoints from ../shared/data, if there) killed
  with part of a file received, then run again: the rerun fetches the file whole (nothing left
  passes for complete) and the model folder equals an uninterrupted download's.

Outputs are compared after leaving out what measures time (`wall_seconds` of rounds.csv,
summary.json's seconds and its computed / from-cache counts, the report's lines of the two);
the figures are compared byte for byte. Prints one line per case and a summary; exits 1 when
any check failed.
"""

from __future__ import annotations

import argparse
import contextlib
import io
import json
import os
import shutil
import signal
import subprocess
import sys
import tempfile
import threading
import time
from collections.abc import Callable
from pathlib import Path

import msgspec
import numpy as np
import pandas as pd

from decoy_cli.evaluate.job import FileIndex
from decoy_cli.evaluate.outputs import LOCK_FILE
from decoy_cli.evaluate.record import RoundRecord
from decoy_cli.synth.sample import SAMPLE_DIR

DECOY = [sys.executable, "-c", "from decoy_cli.cli import app; app()"]
RUN = ["evaluate", str(SAMPLE_DIR), "--sample", "4", "--workers", "2", "--no-combat"]
ROUNDS = 4
RESUME_LINE = "run the same command again to resume"


# ---- running the command ------------------------------------------------------------------------


def start(folder: Path, *extra: str, log: Path | None = None) -> subprocess.Popen:
    """`decoy evaluate ... --out out` in `folder`, in its own process group; its stdout and
    stderr go to `log` (by default `folder`) as run-N.out and run-N.err."""
    log = log or folder
    folder.mkdir(parents=True, exist_ok=True)
    log.mkdir(parents=True, exist_ok=True)
    n = len(list(log.glob("run-*.err")))
    return subprocess.Popen(
        [*DECOY, *RUN, "--out", "out", *extra],
        cwd=folder,
        stdout=(log / f"run-{n}.out").open("w"),
        stderr=(log / f"run-{n}.err").open("w"),
        start_new_session=True,
    )


def finish(process: subprocess.Popen, timeout: float = 600) -> int:
    """Wait for the run, then end what is left of its process group (orphaned workers)."""
    code = process.wait(timeout=timeout)
    end_group(process)
    return code


def end_group(process: subprocess.Popen) -> None:
    with contextlib.suppress(ProcessLookupError, PermissionError):
        os.killpg(process.pid, signal.SIGKILL)


def logs(folder: Path) -> tuple[str, str]:
    """stdout and stderr of the latest run in `folder`."""
    last = max(int(p.stem.split("-")[1]) for p in folder.glob("run-*.err"))
    return (folder / f"run-{last}.out").read_text(), (folder / f"run-{last}.err").read_text()


def run(folder: Path, *extra: str, log: Path | None = None) -> int:
    return finish(start(folder, *extra, log=log))


def wait_for(condition: Callable[[], bool], process: subprocess.Popen, limit: float) -> bool:
    """Poll `condition` until it holds (True) or the process ends or `limit` passes (False)."""
    deadline = time.perf_counter() + limit
    while time.perf_counter() < deadline and process.poll() is None:
        if condition():
            return True
        time.sleep(0.02)
    return False


# ---- what a folder holds ------------------------------------------------------------------------


def outputs(out: Path) -> dict[str, bytes]:
    """The outputs (not the cache, not the lock) by relative path, without what measures time."""
    found = {}
    for path in sorted(out.rglob("*")):
        rel = path.relative_to(out).as_posix()
        if path.is_dir() or rel.startswith("cache/") or rel == LOCK_FILE:
            continue
        found[rel] = _without_time(rel, path.read_bytes())
    return found


def _without_time(rel: str, data: bytes) -> bytes:
    if rel == "rounds.csv":
        frame = pd.read_csv(io.BytesIO(data), dtype=str, keep_default_na=False)
        return frame.drop(columns=["wall_seconds"]).to_csv(index=False).encode()
    if rel == "summary.json":
        summary = json.loads(data)
        for key in ("wall_seconds", "compute_seconds"):
            summary.pop(key, None)
        for key in ("rounds_from_cache", "rounds_computed"):
            summary["counts"].pop(key, None)
        return json.dumps(summary, sort_keys=True).encode()
    if rel == "report.md":
        timed = ("| computed / from cache |", "| wall time |")
        lines = data.decode().splitlines()
        return "\n".join(line for line in lines if not line.startswith(timed)).encode()
    return data


def differences(out: Path, reference: dict[str, bytes]) -> list[str]:
    got = outputs(out)
    missing = sorted(set(reference) - set(got))
    extra = sorted(set(got) - set(reference))
    changed = sorted(k for k in set(got) & set(reference) if got[k] != reference[k])
    return [f"missing {m}" for m in missing] + [f"extra {e}" for e in extra] + changed


def cache_problems(out: Path) -> tuple[list[str], int]:
    """What is wrong in the cache (an entry that does not decode or holds another key, a file
    that is not an entry) and the number of round entries."""
    problems = []
    rounds = 0
    decoders = {
        "rounds": msgspec.msgpack.Decoder(RoundRecord),
        "index": msgspec.msgpack.Decoder(FileIndex),
    }
    for path in sorted((out / "cache").rglob("*")) if (out / "cache").is_dir() else []:
        if path.is_dir():
            continue
        kind = path.parent.name
        if path.suffix != ".msgpack" or kind not in decoders or path.name.startswith("."):
            problems.append(f"stray {path.relative_to(out)}")
            continue
        try:
            entry = decoders[kind].decode(path.read_bytes())
        except msgspec.DecodeError:
            problems.append(f"corrupt {path.relative_to(out)}")
            continue
        if kind == "rounds":
            rounds += 1
            if entry.key != path.stem:
                problems.append(f"misplaced {path.relative_to(out)}")
    return problems, rounds


def leftovers(out: Path) -> list[str]:
    """Temporary files and staging folders anywhere in the output folder."""
    if not out.is_dir():
        return []
    return sorted(
        p.relative_to(out).as_posix()
        for p in out.rglob("*")
        if p.name.startswith(".staging") or p.name.endswith((".tmp", ".check"))
    )


def phase(out: Path) -> str:
    """Where a killed run was, from what it left."""
    if not out.is_dir():
        return "starting"
    if any(p.name.startswith(".staging") for p in out.iterdir()):
        return "writing outputs"
    if (out / "report.md").exists():
        return "publishing or done"
    if not (out / "cache").is_dir():
        return "holding the folder, nothing cached"
    _, rounds = cache_problems(out)
    return f"{rounds} of {ROUNDS} rounds cached"


# ---- the cases ----------------------------------------------------------------------------------


class Results:
    def __init__(self) -> None:
        self.rows: list[tuple[str, bool, str]] = []

    def add(self, case: str, ok: bool, detail: str = "") -> None:
        self.rows.append((case, ok, detail))
        print(f"{'ok  ' if ok else 'FAIL'} {case}{': ' + detail if detail else ''}", flush=True)


def one_error_line(folder: Path, code: int) -> str | None:
    """The problem with a run that should have ended in one `error:` line, or None."""
    _, err = logs(folder)
    lines = err.strip().splitlines()
    if code != 1:
        return f"exit {code}: {err.strip()[-300:]}"
    if "Traceback" in err or len(lines) != 1 or not lines[0].startswith("error: "):
        return f"stderr: {err.strip()[-300:]}"
    return None


def resumed_equal(folder: Path, reference: dict[str, bytes]) -> list[str]:
    """Run again in `folder`; what differs from an uninterrupted run."""
    code = run(folder)
    out = folder / "out"
    problems = [] if code == 0 else [f"rerun exit {code}: {logs(folder)[1].strip()[-200:]}"]
    problems += differences(out, reference)
    cache, rounds = cache_problems(out)
    problems += cache + leftovers(out)
    if rounds != ROUNDS:
        problems.append(f"{rounds} round entries in the cache")
    return problems


def kills(
    work: Path,
    reference: dict[str, bytes],
    window: float,
    from_lock: bool,
    count: int,
    rng: np.random.Generator,
    results: Results,
) -> None:
    """SIGKILL at `count` moments over 1.05 `window` seconds from the start of the run, or from
    the moment it holds its folder (`from_lock`); see the module doc."""
    landed = attempts = 0
    phases: dict[str, int] = {}
    while landed < count and attempts < 3 * count:
        moment = (landed + rng.random()) / count * 1.05 * window
        folder = work / f"kill-{attempts}"
        attempts += 1
        process = start(folder)
        if from_lock:
            wait_for(lambda f=folder: (f / "out" / LOCK_FILE).exists(), process, 600)
        started = time.perf_counter()
        while process.poll() is None and time.perf_counter() - started < moment:
            time.sleep(0.005)
        if process.poll() is not None:
            finish(process)
            shutil.rmtree(folder, ignore_errors=True)
            continue  # the run ended first: not a kill point
        os.kill(process.pid, signal.SIGKILL)
        finish(process)
        landed += 1
        out = folder / "out"
        where = phase(out)
        phases[where] = phases.get(where, 0) + 1
        problems, _ = cache_problems(out)
        problems += [f"after the resume: {p}" for p in resumed_equal(folder, reference)]
        results.add(f"SIGKILL at {moment:.2f} s ({where})", not problems, "; ".join(problems))
        shutil.rmtree(folder, ignore_errors=True)
    print(f"kill points by phase: {phases}")


def interrupts(work: Path, reference: dict[str, bytes], wall: float, count: int, rng, results):
    for i in range(count):
        folder = work / f"interrupt-{i}"
        process = start(folder)
        if not wait_for(lambda f=folder: (f / "out" / LOCK_FILE).exists(), process, 600):
            finish(process)
            results.add(f"Ctrl-C {i}", False, "the run never held its folder")
            continue
        time.sleep(rng.random() * 0.8 * wall)
        where = phase(folder / "out")
        with contextlib.suppress(ProcessLookupError):
            os.killpg(process.pid, signal.SIGINT)
        code = finish(process)
        out, err = logs(folder)
        problems = []
        if code == 0:
            where = "done before the signal"
        elif "outputs written to" in out and code in (130, -signal.SIGINT):
            where = "after the outputs were written"  # nothing to resume; checked below
        elif code != 130 or RESUME_LINE not in " ".join(out.split()):
            problems.append(f"exit {code}, no resume line: {(out + err).strip()[-300:]}")
        if "Traceback" in err:
            problems.append("traceback")
        problems += cache_problems(folder / "out")[0]
        problems += [f"after the resume: {p}" for p in resumed_equal(folder, reference)]
        results.add(f"Ctrl-C {i} ({where})", not problems, "; ".join(problems))
        shutil.rmtree(folder, ignore_errors=True)


def lock(work: Path, reference: dict[str, bytes], results: Results) -> None:
    folder = work / "lock-live"
    first = start(folder)
    if not wait_for(lambda: (folder / "out" / LOCK_FILE).exists(), first, 600):
        results.add("second run while one is live", False, "the first run never held the folder")
    else:
        second = subprocess.run(
            [*DECOY, *RUN, "--out", "out"], cwd=folder, capture_output=True, text=True
        )
        lines = second.stderr.strip().splitlines()
        refused = (
            second.returncode == 1
            and len(lines) == 1
            and "another decoy evaluate" in lines[0]
            and lines[0].startswith("error: ")
        )
        results.add("second run while one is live: refused", refused, second.stderr.strip())
    code = finish(first)
    problems = ([] if code == 0 else [f"exit {code}"]) + differences(folder / "out", reference)
    results.add("the live run beside the refused one", not problems, "; ".join(problems))

    folder = work / "lock-killed"
    first = start(folder)
    if wait_for(lambda: (folder / "out" / LOCK_FILE).exists(), first, 600):
        os.kill(first.pid, signal.SIGKILL)
    finish(first)
    problems = resumed_equal(folder, reference)
    results.add("a run after one killed holding the lock", not problems, "; ".join(problems))

    folder = work / "lock-reused"
    (folder / "out").mkdir(parents=True)
    (folder / "out" / LOCK_FILE).write_text(f"{os.getpid()}\n")  # alive, and no decoy run
    problems = resumed_equal(folder, reference)
    results.add("a lock naming a live process that is no run", not problems, "; ".join(problems))


def disk(work: Path, reference: dict[str, bytes], results: Results) -> None:
    mount = work / "mnt"
    mount.mkdir()

    def tmpfs(size: str) -> bool:
        done = subprocess.run(
            ["mount", "-t", "tmpfs", "-o", f"size={size}", "tmpfs", str(mount)],
            capture_output=True,
            text=True,
        )
        if done.returncode != 0:
            results.add("disk cases", True, f"skipped: cannot mount a tmpfs: {done.stderr.strip()}")
        return done.returncode == 0

    def error_line(name: str, *extra: str) -> list[str]:
        log = work / "disk-logs" / name
        problem = one_error_line(log, run(mount / "run", *extra, log=log))
        seen.append(logs(log)[1].strip())
        return [problem] if problem else []

    def unmount() -> None:
        for _ in range(50):  # a worker the run left may still have the folder open
            if subprocess.run(["umount", str(mount)], capture_output=True).returncode == 0:
                return
            time.sleep(0.1)
        subprocess.run(["umount", "-l", str(mount)], check=False)

    seen: list[str] = []

    out = mount / "run" / "out"
    if not tmpfs("200k"):
        return
    try:
        problems = error_line("small")
        written = sorted(outputs(out)) if out.is_dir() else []
        problems += [f"written: {w}" for w in written] + leftovers(out) + cache_problems(out)[0]
        results.add("a run onto a 200 kB disk", not problems, _detail(problems, seen[-1]))
    finally:
        unmount()
    if not tmpfs("24m"):
        return
    try:
        if run(mount / "run", log=work / "disk-logs" / "good") != 0:
            results.add("a good run before the full disk", False, "it failed")
            return
        before = {p: p.read_bytes() for p in out.rglob("*") if p.is_file()}
        free = shutil.disk_usage(mount).free
        (mount / "filler").write_bytes(b"\0" * max(free - 64 * 1024, 0))
        problems = error_line("full-outputs")  # every round cached: only outputs to write
        problems += _changed(before, out) + leftovers(out) + cache_problems(out)[0]
        results.add("the same run onto a full disk", not problems, _detail(problems, seen[-1]))
        problems = error_line("full", "--seed", "1")
        problems += _changed(before, out) + leftovers(out) + cache_problems(out)[0]
        results.add("another seed onto a full disk", not problems, _detail(problems, seen[-1]))
        (mount / "filler").unlink()
        subprocess.run(["mount", "-o", "remount,ro", str(mount)], check=True)
        problems = error_line("read-only", "--seed", "1") + _changed(before, out)
        results.add("a read-only output folder", not problems, _detail(problems, seen[-1]))
    finally:
        unmount()


def _changed(before: dict[Path, bytes], out: Path) -> list[str]:
    after = {p: p.read_bytes() for p in out.rglob("*") if p.is_file()}
    changed = [p for p in before if p.name != LOCK_FILE and after.get(p) != before[p]]
    new = [p for p in after if p not in before and "cache" not in p.parts and p.name != LOCK_FILE]
    return [f"changed {p.relative_to(out)}" for p in changed] + [
        f"new {p.relative_to(out)}" for p in new
    ]


# ---- downloads cut by a SIGKILL ----------------------------------------------------------------

UUID = "00000000-0000-4000-8000-000000000035"
PAPER_CHECKPOINTS = Path(__file__).resolve().parents[2].parent / "shared/data/decoy_checkpoints"


class _Server:
    """A local HTTP server of `files` (URL path -> bytes) that, while `stall` names a path,
    sends the first half of that file and then holds the connection."""

    def __init__(self, files: dict[str, bytes]) -> None:
        from http.server import BaseHTTPRequestHandler, ThreadingHTTPServer

        server = self
        self.files, self.stall, self.release = files, "", threading.Event()

        class Handler(BaseHTTPRequestHandler):
            def do_GET(self) -> None:
                body = server.files.get(self.path)
                if body is None:
                    self.send_error(404)
                    return
                self.send_response(200)
                self.send_header("Content-Length", str(len(body)))
                self.end_headers()
                if self.path == server.stall:
                    self.wfile.write(body[: len(body) // 2])
                    self.wfile.flush()
                    server.release.wait(120)
                    return
                self.wfile.write(body)

            def log_message(self, *args: object) -> None:
                pass

        self.httpd = ThreadingHTTPServer(("127.0.0.1", 0), Handler)
        self.httpd.daemon_threads = True
        threading.Thread(target=self.httpd.serve_forever, daemon=True).start()
        self.url = f"http://127.0.0.1:{self.httpd.server_port}"

    def close(self) -> None:
        self.release.set()
        self.httpd.shutdown()


def _cut_then_rerun(
    command: list[str], cwd: Path, part_folder: Path, server: _Server, path: str
) -> list[str]:
    """Run `command` while the server stalls on `path` after half of it, SIGKILL it once its
    temporary file has data, then run it again with the server whole; the problems."""
    server.stall, server.release = path, threading.Event()
    cwd.mkdir(parents=True, exist_ok=True)
    process = subprocess.Popen(command, cwd=cwd, start_new_session=True, **_QUIET)

    def some_in() -> bool:
        parts = list(part_folder.glob(".*.part")) if part_folder.is_dir() else []
        return any(p.stat().st_size > 0 for p in parts)

    problems = [] if wait_for(some_in, process, 30) else ["the download never began"]
    time.sleep(0.5)  # the client holds what the server sent (up to half the file)
    with contextlib.suppress(ProcessLookupError):
        os.kill(process.pid, signal.SIGKILL)
    code = finish(process)
    if code != -signal.SIGKILL:
        problems.append(f"the cut download ended by itself (exit {code})")
    server.release.set()
    server.stall = ""
    rerun = subprocess.run(command, cwd=cwd, capture_output=True, text=True, timeout=600)
    if rerun.returncode != 0:
        problems.append(f"rerun exit {rerun.returncode}: {rerun.stderr.strip()[-300:]}")
    return problems


_QUIET = {"stdout": subprocess.DEVNULL, "stderr": subprocess.DEVNULL}


def _detail(problems: list[str], note: str) -> str:
    return "; ".join([*problems, note])


def downloads(work: Path, results: Results) -> None:
    match = sorted(SAMPLE_DIR.glob("*.json.xz"))[0].read_bytes()
    server = _Server({f"/lan/{UUID}.json.xz": match})
    try:
        dest = work / "download" / "esta"
        command = [*DECOY, "download", UUID, "--dest", str(dest), "--base-url", server.url]
        problems = _cut_then_rerun(command, work / "download", dest, server, f"/lan/{UUID}.json.xz")
        target = dest / f"{UUID}.json.xz"
        if not target.is_file() or target.read_bytes() != match:
            problems.append("the rerun did not place the whole file")
        left = f"{len(list(dest.glob('.*.part')))} temporary .part file(s) of the cut run left"
        detail = _detail(problems, left)
        results.add("decoy download cut mid-file, then again", not problems, detail)
    finally:
        server.close()
    if not PAPER_CHECKPOINTS.is_dir():
        results.add("models download-decoy", True, f"skipped: no {PAPER_CHECKPOINTS}")
        return
    from decoy_cli.modeling.paper_download import PAPER_FILES

    files = {
        f"/{f.path}": (PAPER_CHECKPOINTS / name).read_bytes() for name, f in PAPER_FILES.items()
    }
    server = _Server(files)
    try:
        clean, cut = work / "models" / "clean", work / "models" / "cut"
        whole = [*DECOY, "models", "download-decoy", "--base-url", server.url, "--out"]
        problems = []
        if subprocess.run([*whole, str(clean)], capture_output=True).returncode != 0:
            problems.append("the uninterrupted download failed")
        stall = f"/{PAPER_FILES['dog_best_model.pth'].path}"
        problems += _cut_then_rerun(
            [*whole, str(cut)], work / "models", cut / "checkpoints", server, stall
        )
        for name in ("dip.pt", "dip.json", "dog.pt", "dog.json"):
            if (
                not (cut / name).is_file()
                or (cut / name).read_bytes() != (clean / name).read_bytes()
            ):
                problems.append(f"{name} differs from an uninterrupted download's")
        left = f"{len(list((cut / 'checkpoints').glob('.*.part')))} .part file(s) left"
        results.add(
            "models download-decoy cut mid-file, then again", not problems, _detail(problems, left)
        )
    finally:
        server.close()


def _reference(work: Path) -> tuple[dict[str, bytes], float, float]:
    """The outputs of an uninterrupted run, its wall time and the time it held its folder
    (after a warm-up run that compiles what a first run compiles)."""
    run(work / "warm-up")
    shutil.rmtree(work / "warm-up", ignore_errors=True)
    started = time.perf_counter()
    process = start(work / "reference")
    wait_for(lambda: (work / "reference" / "out" / LOCK_FILE).exists(), process, 600)
    held = time.perf_counter()
    if finish(process) != 0:
        raise SystemExit(f"the reference run failed: {logs(work / 'reference')[1]}")
    wall, held = time.perf_counter() - started, time.perf_counter() - held
    reference = outputs(work / "reference" / "out")
    print(f"reference: {len(reference)} outputs, {wall:.1f} s, {held:.1f} s holding its folder")
    return reference, wall, held


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--kills", type=int, default=50)
    parser.add_argument("--interrupts", type=int, default=10)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument(
        "--from-lock",
        action="store_true",
        help="draw the kill moments over the time the run holds its folder (not from its start)",
    )
    parser.add_argument("--only", default="kills,interrupts,lock,disk,downloads")
    parser.add_argument("--keep", type=Path, help="work in this folder and keep it")
    args = parser.parse_args()
    work = args.keep or Path(tempfile.mkdtemp(prefix="decoy-crash-"))
    work.mkdir(parents=True, exist_ok=True)
    rng = np.random.default_rng(args.seed)
    results = Results()
    chosen = args.only.split(",")
    try:
        if set(chosen) - {"downloads"}:
            reference, wall, held = _reference(work)
        if "kills" in chosen:
            window = held if args.from_lock else wall
            kills(work, reference, window, args.from_lock, args.kills, rng, results)
        if "interrupts" in chosen:
            interrupts(work, reference, wall, args.interrupts, rng, results)
        if "lock" in chosen:
            lock(work, reference, results)
        if "disk" in chosen:
            disk(work, reference, results)
        if "downloads" in chosen:
            downloads(work, results)
    finally:
        if args.keep is None:
            shutil.rmtree(work, ignore_errors=True)
    failed = [row for row in results.rows if not row[1]]
    print(f"{len(results.rows) - len(failed)} of {len(results.rows)} cases passed")
    raise SystemExit(1 if failed else 0)


if __name__ == "__main__":
    main()
