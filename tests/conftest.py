"""Fixtures shared by several test modules."""

from __future__ import annotations

import os
from pathlib import Path

import pytest
from typer.testing import CliRunner

from decoy_cli.cli import app

SAMPLE = Path(__file__).resolve().parents[1] / "examples" / "sample"

# One thread per torch (OpenMP) runtime: the suite runs in `-n 2` workers on two cores, where a
# torch that spins a thread per core in each worker waits on the other worker's tests. Read
# when torch first loads, so set before any test imports it.
os.environ.setdefault("OMP_NUM_THREADS", "1")
# `decoy evaluate` runs its rounds in the test's own process unless a test asks for worker
# processes (`--workers N`, which the tests of the pool, its crashes and Ctrl-C give): starting
# a pool and loading the package again in each worker cost seconds per run.
os.environ.setdefault("DECOY_WORKERS", "0")


@pytest.fixture(scope="session")
def run(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """One `decoy evaluate` of the shipped sample, for the view's tests (once per test process;
    a test that changes a run changes a copy of it). In this process: the suite's two test
    processes already keep both cores busy, and a pool would load the package twice more."""
    out = tmp_path_factory.mktemp("run") / "evaluate"
    args = ["evaluate", str(SAMPLE), "--out", str(out), "--workers", "0", "--no-figures"]
    result = CliRunner().invoke(app, args)
    assert result.exit_code == 0, result.output
    return out
