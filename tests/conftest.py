"""Fixtures shared by several test modules."""

from __future__ import annotations

from pathlib import Path

import pytest
from typer.testing import CliRunner

from decoy_cli.cli import app

SAMPLE = Path(__file__).resolve().parents[1] / "examples" / "sample"


@pytest.fixture(scope="session")
def run(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """One `decoy evaluate` of the shipped sample, for the view's tests (once per test process;
    a test that changes a run changes a copy of it)."""
    out = tmp_path_factory.mktemp("run") / "evaluate"
    result = CliRunner().invoke(app, ["evaluate", str(SAMPLE), "--out", str(out), "--workers", "2"])
    assert result.exit_code == 0, result.output
    return out
