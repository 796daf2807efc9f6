"""Stamps of the shipped waypoint graphs: a fingerprint of everything each is built from.

A shipped graph (`assets/<map>/waypoints.npz`, and de_dust2's `cs2_waypoints.npz`) is checked by
rebuilding it byte for byte (tests/test_build_waypoints_cli.py, tests/test_cs2_world.py). The
build is deterministic, so its bytes can only change when its inputs do: the builder's code
(`decoy_cli/world`, `decoy_cli/waypoints`, the package's top-level modules and the command),
the map's asset files (nav mesh, places, patches, ladders), the CS2 nav file for the CS2 graph,
and the Python, numpy, scipy, numba and pybullet versions. Each graph has a stamp beside it
(`<graph>.inputs`, not shipped in the package): the fingerprint of those inputs at which its
bytes were last rebuilt and found equal. The tests rebuild a graph only when its fingerprint
differs from its stamp; this script rebuilds each graph whose stamp is stale, checks its
bytes and writes the stamp (it refuses when the bytes differ: rebuild that graph on purpose).

    python scripts/graph_stamps.py [--check]   # --check: only say which stamps are stale
"""

from __future__ import annotations

import argparse
import hashlib
import os
import subprocess
import sys
import tempfile
from importlib.metadata import version
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
ASSETS = ROOT / "assets"
PACKAGE = ROOT / "decoy_cli"
CS2_NAV = ROOT.parent / "shared" / "data" / "cs2_maps" / "de_dust2.nav.json.xz"
"""The nav file the shipped CS2 de_dust2 graph is built from (../shared/data)."""
CODE = [
    *sorted((PACKAGE / "world").rglob("*.py")),
    *sorted((PACKAGE / "waypoints").rglob("*.py")),
    *sorted(PACKAGE.glob("*.py")),
    PACKAGE / "commands" / "build_waypoints.py",
]
LIBRARIES = ("numpy", "scipy", "numba", "pybullet")
NOT_INPUTS = {".npz", ".inputs", ".md", ".png"}
"""Files of a map's asset folder that are outputs or text, not what its graph is built from."""


def shipped_graphs() -> list[tuple[str, str]]:
    """(map, graph file name) of every shipped graph."""
    graphs = []
    for folder in sorted(p for p in ASSETS.iterdir() if p.is_dir()):
        for name in ("waypoints.npz", "cs2_waypoints.npz"):
            if (folder / name).is_file():
                graphs.append((folder.name, name))
    return graphs


def build_arguments(map_name: str, graph_file: str, out: Path) -> list[str]:
    """`decoy build-waypoints`'s arguments that rebuild a shipped graph into `out`."""
    if graph_file == "cs2_waypoints.npz":
        return ["build-waypoints", "--nav", str(CS2_NAV), "--out", str(out), "--no-plot"]
    return ["build-waypoints", "--map", map_name, "--out", str(out), "--no-plot"]


def fingerprint(map_name: str, graph_file: str) -> str:
    """The fingerprint of what a shipped graph is built from (module docstring)."""
    digest = hashlib.sha256()
    named = [(str(path.relative_to(PACKAGE.parent)), path) for path in CODE]
    assets = sorted(p for p in (ASSETS / map_name).iterdir() if p.suffix not in NOT_INPUTS)
    named += [(f"assets/{map_name}/{path.name}", path) for path in assets]
    if graph_file == "cs2_waypoints.npz":
        named.append(("the CS2 nav file", CS2_NAV))
    for name, path in named:
        digest.update(name.encode())
        digest.update(path.read_bytes() if path.is_file() else b"absent")
    libraries = [f"python {sys.version_info.major}.{sys.version_info.minor}"]
    libraries += [f"{name} {version(name)}" for name in LIBRARIES]
    digest.update("\n".join(libraries).encode())
    return digest.hexdigest()


def stamp_path(map_name: str, graph_file: str) -> Path:
    return ASSETS / map_name / graph_file.replace(".npz", ".inputs")


def stamp_is_current(map_name: str, graph_file: str) -> bool:
    """Whether the graph's bytes were last checked at its inputs' present fingerprint."""
    path = stamp_path(map_name, graph_file)
    return path.is_file() and path.read_text().strip() == fingerprint(map_name, graph_file)


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--check", action="store_true", help="only say which stamps are stale")
    args = parser.parse_args()
    stale = [(m, g) for m, g in shipped_graphs() if not stamp_is_current(m, g)]
    for map_name, graph_file in stale:
        print(f"{map_name}/{graph_file}: stamp stale")
    if args.check or not stale:
        print(f"{len(stale)} of {len(shipped_graphs())} stamps stale")
        return 1 if args.check and stale else 0
    failed = 0
    with tempfile.TemporaryDirectory() as tmp:
        for map_name, graph_file in stale:
            out = Path(tmp) / graph_file
            command = [sys.executable, "-m", "decoy_cli.entry"]
            command += build_arguments(map_name, graph_file, out)
            environment = {**os.environ, "PYTHONPATH": str(ROOT)}  # this checkout's code
            built = subprocess.run(command, capture_output=True, text=True, env=environment)
            shipped = ASSETS / map_name / graph_file
            if built.returncode != 0 or out.read_bytes() != shipped.read_bytes():
                print(f"{map_name}/{graph_file}: the rebuild differs from the shipped bytes: "
                      "rebuild it on purpose; stamp left as it was")  # fmt: skip
                failed += 1
                continue
            stamp_path(map_name, graph_file).write_text(fingerprint(map_name, graph_file) + "\n")
            print(f"{map_name}/{graph_file}: rebuilt byte for byte; stamped")
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
