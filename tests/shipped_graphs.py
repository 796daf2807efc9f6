"""The shipped graphs' byte-for-byte rebuilds, run when their inputs changed: the stamps of
scripts/graph_stamps.py say when."""

from __future__ import annotations

import importlib
import sys
import warnings
from pathlib import Path
from types import ModuleType

import pytest
from differences import npz_difference
from typer.testing import CliRunner

from decoy_cli.cli import app
from decoy_cli.world.nav_data import asset_dir

SCRIPTS = Path(__file__).resolve().parents[1] / "scripts"


def graph_stamps() -> ModuleType:
    """scripts/graph_stamps.py (its folder put on the path, as running it does)."""
    if str(SCRIPTS) not in sys.path:
        sys.path.insert(0, str(SCRIPTS))
    return importlib.import_module("graph_stamps")


def assert_rebuilt_when_inputs_changed(map_name: str, graph_file: str, tmp_path: Path) -> None:
    """The shipped graph rebuilt byte for byte, unless its stamp is current: the build is
    deterministic, so while its inputs' fingerprint is the one stamped when its bytes were last
    rebuilt and found equal, the rebuild cannot differ (a skip that says so). A stale stamp
    whose rebuild passes is a warning to run scripts/graph_stamps.py."""
    stamps = graph_stamps()
    if stamps.stamp_is_current(map_name, graph_file):
        pytest.skip("inputs unchanged since the rebuild was checked (scripts/graph_stamps.py)")
    out = tmp_path / graph_file
    arguments = stamps.build_arguments(map_name, graph_file, out)
    result = CliRunner().invoke(app, arguments, env={"COLUMNS": "200"})
    assert result.exit_code == 0, result.output
    shipped = asset_dir(map_name) / graph_file
    assert out.read_bytes() == shipped.read_bytes(), npz_difference(out, shipped)
    stale = f"{map_name}/{graph_file}: stamp stale; run python scripts/graph_stamps.py"
    warnings.warn(stale, stacklevel=2)
