"""The wheel: built from a copy of the source tree, it holds the map assets and the shipped damage
models (the top-level `assets/` and `models/`, mapped into the package by setup.py), and an
install of it loads them from the install, not from the source tree.

Builds offline (`pip wheel --no-deps --no-build-isolation --no-index`) with the setuptools at
hand; skips when pip or a wheel-capable setuptools is missing. About 10 s.
"""

from __future__ import annotations

import importlib.util
import shutil
import subprocess
import sys
import textwrap
import zipfile
from importlib import metadata
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
SOURCES = ("pyproject.toml", "setup.py", "README.md", "decoy_cli", "assets", "models")
SHIPPED = ("assets", "models")
REQUIRED = (
    "decoy_cli/assets/de_dust2/waypoints.npz",
    "decoy_cli/assets/de_dust2/nav_areas.csv",
    "decoy_cli/assets/de_dust2/nav_connections.csv",
    "decoy_cli/assets/de_dust2/map.json",
    "decoy_cli/assets/de_dust2/world_patches.csv",
    "decoy_cli/assets/de_dust2/ATTRIBUTION.md",
    "decoy_cli/models/dip.pt",
    "decoy_cli/models/dip.json",
    "decoy_cli/models/DIP_CARD.md",
    "decoy_cli/models/dog.pt",
    "decoy_cli/models/dog.json",
    "decoy_cli/models/DOG_CARD.md",
    "decoy_cli/cli.py",
    "decoy_cli/view/page.html",
    "decoy_cli/view/data.js",
    "decoy_cli/view/draw.js",
    "decoy_cli/view/controls.js",
    "decoy_cli/view/tables.js",
    "decoy_cli/view/page.css",
)

# Run in the install: every path must come from it, and the data must load.
CHECK = textwrap.dedent(
    """
    import sys
    from pathlib import Path

    target = Path(sys.argv[1]).resolve()
    import decoy_cli
    from decoy_cli.damage import SHIPPED_MODELS, load_damage_model, shipped_models_installed
    from decoy_cli.package_data import packaged_dir
    from decoy_cli.waypoints.build import builtin_graph
    from decoy_cli.world.navmesh import asset_dir, load_navmesh, load_patches

    for path in (Path(decoy_cli.__file__), packaged_dir("assets"), asset_dir(), SHIPPED_MODELS):
        assert path.resolve().is_relative_to(target), f"{path} is not in {target}"
    graph = builtin_graph()
    assert graph.num_nodes > 1000 and graph.num_edges > graph.num_nodes, graph
    assert load_navmesh().num_areas > 1000
    assert len(load_patches()) >= 1
    assert shipped_models_installed()
    assert load_damage_model("shipped") is not None
    print("ok", graph.num_nodes, SHIPPED_MODELS)
    """
)


def _can_build() -> str | None:
    """Why the wheel cannot be built offline here, or None."""
    if importlib.util.find_spec("pip") is None:
        return "pip is not installed"
    try:  # not imported here: importing setuptools in the test process can clash with distutils
        version = metadata.version("setuptools")
    except metadata.PackageNotFoundError:
        return "setuptools is not installed (the build runs without isolation, offline)"
    major, minor = (int(part) for part in version.split(".")[:2])
    if (major, minor) < (68, 0):
        return f"setuptools {version} is older than pyproject.toml's setuptools>=68"
    if (major, minor) < (70, 1) and importlib.util.find_spec("wheel") is None:
        return f"setuptools {version} needs the wheel package to build wheels"
    return None


def _pip(*args: str, cwd: Path) -> None:
    result = subprocess.run(
        [sys.executable, "-m", "pip", *args, "--no-deps", "--no-index", "-q"],
        cwd=cwd,
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert result.returncode == 0, f"pip {args[0]} failed:\n{result.stdout}\n{result.stderr}"


@pytest.fixture(scope="module")
def wheel(tmp_path_factory: pytest.TempPathFactory) -> Path:
    reason = _can_build()
    if reason:
        pytest.skip(f"cannot build the wheel offline: {reason}")
    # A copy of the source, so the build's build/ and *.egg-info stay out of the checkout and no
    # stale build/lib file from an earlier build can slip into the wheel.
    source = tmp_path_factory.mktemp("source")
    for name in SOURCES:
        path = ROOT / name
        if path.is_dir():
            shutil.copytree(path, source / name, ignore=shutil.ignore_patterns("__pycache__"))
        else:
            shutil.copy2(path, source / name)
    out = tmp_path_factory.mktemp("wheel")
    _pip("wheel", str(source), "--no-build-isolation", "-w", str(out), cwd=out)
    (built,) = out.glob("decoy-*.whl")
    return built


def test_the_wheel_holds_the_assets_and_models(wheel: Path) -> None:
    with zipfile.ZipFile(wheel) as archive:
        names = set(archive.namelist())
    missing = [name for name in REQUIRED if name not in names]
    assert not missing, f"missing from {wheel.name}: {missing}"
    # Every shipped file of the source tree, not only the ones named above; the graphs' stamps
    # (scripts/graph_stamps.py) are the tests' business, not an installed package's.
    for folder in SHIPPED:
        for path in sorted((ROOT / folder).rglob("*")):
            if path.is_file() and "__pycache__" not in path.parts and path.suffix != ".inputs":
                name = f"decoy_cli/{path.relative_to(ROOT).as_posix()}"
                assert name in names, f"{name} is missing from {wheel.name}"
    assert not [n for n in names if n.startswith(("assets/", "models/"))], "top-level data"


def test_an_install_of_the_wheel_loads_its_own_data(wheel: Path, tmp_path: Path) -> None:
    target = tmp_path / "site"
    _pip("install", "--target", str(target), str(wheel), cwd=tmp_path)
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    result = subprocess.run(
        [sys.executable, "-c", CHECK, str(target)],
        cwd=elsewhere,
        env={"PYTHONPATH": str(target), "PATH": "/usr/bin:/bin", "HOME": str(tmp_path)},
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert result.returncode == 0, result.stdout + result.stderr
    assert result.stdout.startswith("ok ")
