"""scripts/graph_stamps.py: a shipped graph's stamp is current only while nothing it is built
from changed."""

from __future__ import annotations

import shutil
from pathlib import Path

import pytest
from shipped_graphs import graph_stamps


def test_a_stamp_goes_stale_when_a_map_file_or_the_code_changes(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    stamps = graph_stamps()
    before = stamps.fingerprint("de_vertigo", "waypoints.npz")
    assets = tmp_path / "assets"
    shutil.copytree(stamps.ASSETS / "de_vertigo", assets / "de_vertigo")
    monkeypatch.setattr(stamps, "ASSETS", assets)
    assert stamps.fingerprint("de_vertigo", "waypoints.npz") == before  # where it lies: no input
    stamp = assets / "de_vertigo" / "waypoints.inputs"
    stamp.write_text(before + "\n")
    assert stamps.stamp_is_current("de_vertigo", "waypoints.npz")

    areas = assets / "de_vertigo" / "nav_areas.csv"
    areas.write_bytes(areas.read_bytes() + b"\n")
    assert not stamps.stamp_is_current("de_vertigo", "waypoints.npz")
    areas.write_bytes(areas.read_bytes()[:-1])
    assert stamps.stamp_is_current("de_vertigo", "waypoints.npz")

    package = tmp_path / "decoy_cli"
    package.mkdir()
    code = package / "flood.py"
    code.write_text("# the builder\n")
    monkeypatch.setattr(stamps, "PACKAGE", package)
    monkeypatch.setattr(stamps, "CODE", [code])
    stamp.write_text(stamps.fingerprint("de_vertigo", "waypoints.npz") + "\n")
    assert stamps.stamp_is_current("de_vertigo", "waypoints.npz")
    code.write_text("# the builder, changed\n")
    assert not stamps.stamp_is_current("de_vertigo", "waypoints.npz")


def test_every_shipped_graph_has_a_way_to_be_rebuilt() -> None:
    stamps = graph_stamps()
    graphs = stamps.shipped_graphs()
    assert ("de_dust2", "cs2_waypoints.npz") in graphs and len(graphs) == 9
    for map_name, graph_file in graphs:
        arguments = stamps.build_arguments(map_name, graph_file, Path("out.npz"))
        assert arguments[0] == "build-waypoints" and "--out" in arguments
