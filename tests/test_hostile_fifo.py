"""A FIFO (or any file that is not a regular file) named like a match, a table or a model file
(issue 51): opening it for reading would block forever. Data opens only regular files; anything
else is a named per-file failure in a batch, or one `error:` line.

The commands run in a child process with a time limit, so a hang fails the test instead of
hanging it."""

from __future__ import annotations

import csv
import json
import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest
from esta_fixtures import make_match, write_match
from run_fixtures import write_run

from decoy_cli.errors import DecoyError, EstaError
from decoy_cli.esta import read_match
from decoy_cli.esta.content import content_sha256
from decoy_cli.reading import load_json, open_regular

ROOT = Path(__file__).resolve().parents[1]
LIMIT_S = 300
"""Far more than each command takes; a command still running then is hung."""
FIFOS = ("x.json.xz", "y.json", "z.zip")
"""FIFOs named like an ESTA file, a plain JSON match and an awpy 2 zip."""


def decoy(*args: str, cwd: Path) -> subprocess.CompletedProcess[str]:
    """`decoy ARGS` in a child process, ended by a failed test after `LIMIT_S`."""
    command = [sys.executable, "-c", "from decoy_cli.entry import main; main()", *args]
    try:
        return subprocess.run(
            command,
            cwd=cwd,
            env={**os.environ, "COLUMNS": "1000"},
            capture_output=True,
            text=True,
            timeout=LIMIT_S,
            check=False,
        )
    except subprocess.TimeoutExpired:
        pytest.fail(f"decoy {' '.join(args)} still ran after {LIMIT_S} s (hung on a FIFO?)")


def evaluate_tables(data: Path, out: Path) -> None:
    """`decoy evaluate` of `data` into `out`, tables only: failures are recorded (exit 1), not
    a bug (exit 2), and no traceback is printed."""
    done = decoy(
        "evaluate", str(data), "--no-combat", "--no-view", "--no-figures", "--out", str(out),
        cwd=out.parent,
    )  # fmt: skip
    assert done.returncode == 1, done.stderr
    assert "internal error" not in done.stderr and "Traceback" not in done.stderr


@pytest.fixture
def data(tmp_path: Path) -> Path:
    """A folder of one good match and FIFOs named like matches."""
    folder = tmp_path / "data"
    folder.mkdir()
    write_match(folder / "good.json", make_match())
    for name in FIFOS:
        os.mkfifo(folder / name)
    return folder


def test_evaluate_names_each_fifo_and_writes_the_good_rounds(data: Path, tmp_path: Path) -> None:
    out = tmp_path / "out"
    evaluate_tables(data, out)
    with (out / "failures.csv").open(newline="") as handle:
        failures = {Path(row["file"]).name: row["message"] for row in csv.DictReader(handle)}
    for name in FIFOS:
        assert "not a regular file (a FIFO)" in failures[name], failures
    with (out / "rounds.csv").open(newline="") as handle:
        assert len(list(csv.DictReader(handle))) == 2  # the good match's rounds with frames


def test_info_names_each_fifo_of_a_folder(data: Path, tmp_path: Path) -> None:
    done = decoy("info", str(data), cwd=tmp_path)
    assert done.returncode == 1, done.stderr
    assert "internal error" not in done.stderr and "Traceback" not in done.stderr
    assert done.stderr.strip().splitlines()[-1].startswith("error: ")
    for name in FIFOS:
        assert f"{data / name}: not a regular file" in done.stdout


def test_the_readers_refuse_a_fifo_without_opening_it(data: Path) -> None:
    fifo = data / "x.json.xz"
    with pytest.raises(EstaError, match=r"not a regular file \(a FIFO\)"):
        read_match(fifo)
    with pytest.raises(EstaError, match=r"not a regular file \(a FIFO\)"):
        content_sha256(fifo)
    with pytest.raises(DecoyError, match=r"not a regular file \(a FIFO\)"):
        load_json(fifo)
    with pytest.raises(DecoyError, match="is a folder, not a file"):
        open_regular(data)


@pytest.mark.parametrize("name", ["rounds.csv", "players.csv", "tables/places.csv"])
def test_compare_refuses_a_fifo_in_a_run(tmp_path: Path, name: str) -> None:
    a, b = write_run(tmp_path / "a"), write_run(tmp_path / "b")
    (a / name).unlink()
    os.mkfifo(a / name)
    done = decoy("compare", str(a), str(b), "--out", str(tmp_path / "cmp"), cwd=tmp_path)
    assert done.returncode == 1, done.stderr
    assert done.stderr.strip() == f"error: {a / name}: not a regular file (a FIFO)"


def test_a_fifo_in_a_model_folder_is_one_error_line(tmp_path: Path) -> None:
    folder = tmp_path / "models"
    folder.mkdir()
    for name in ("dip.pt", "dip.json", "rules.json"):
        shutil.copy(ROOT / "models" / name, folder / name)
    write_match(tmp_path / "m.json", make_match())
    for name in ("rules.json", "dip.json"):
        (folder / name).unlink()
        os.mkfifo(folder / name)
        done = decoy(
            "replay",
            f"{tmp_path / 'm.json'}:1",
            "--models",
            str(folder),
            "--out",
            "r",
            cwd=tmp_path,
        )
        assert done.returncode == 1, done.stderr
        assert f"{folder / name}: not a regular file (a FIFO)" in done.stderr


def test_a_fifo_as_weights_is_one_error_line(tmp_path: Path) -> None:
    folder = tmp_path / "models"
    folder.mkdir()
    for name in ("dip.json", "rules.json"):
        shutil.copy(ROOT / "models" / name, folder / name)
    os.mkfifo(folder / "dip.pt")
    write_match(tmp_path / "m.json", make_match())
    done = decoy(
        "replay", f"{tmp_path / 'm.json'}:1", "--models", str(folder), "--out", "r", cwd=tmp_path
    )
    assert done.returncode == 1, done.stderr
    assert done.stderr.strip() == f"error: {folder / 'dip.pt'}: not a regular file (a FIFO)"


def test_evaluate_over_one_bad_file_of_each_kind_keeps_the_good(tmp_path: Path) -> None:
    data = tmp_path / "data"
    data.mkdir()
    for name in ("a.json", "z.json.xz"):
        write_match(data / name, make_match() | {"matchID": name})
    bad = {
        "deep.json": "[" * 100_000 + "]" * 100_000,
        "truncated.json": json.dumps(make_match())[:5000],
        "empty.json": "",
        "binary.json.xz": "\xfd7zXZ\x00 not really xz",
    }
    for name, text in bad.items():
        (data / name).write_text(text, encoding="latin-1")
    os.mkfifo(data / "fifo.json.xz")
    (data / "folder.json").mkdir()
    (data / "loop.json").symlink_to(data / "loop.json")
    out = tmp_path / "out"
    evaluate_tables(data, out)
    with (out / "failures.csv").open(newline="") as handle:
        failed = {Path(row["file"]).name for row in csv.DictReader(handle)}
    assert {*bad, "fifo.json.xz", "loop.json"} <= failed, failed
    with (out / "rounds.csv").open(newline="") as handle:
        matches = {row["match"] for row in csv.DictReader(handle)}
    assert matches == {"a.json", "z.json.xz"}
