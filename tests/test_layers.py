"""Imports run down the layers, never back up (the design's layout): a module may import its
own package and any lower layer, including imports inside functions and for type checking."""

from __future__ import annotations

import ast
from pathlib import Path

PACKAGE = Path(__file__).resolve().parents[1] / "decoy_cli"

LAYERS = {
    # shared facts and helpers
    "csgo": 0,
    "geometry": 0,  # facing, bearings, the eye point: on csgo's eye height
    "compiled": 0,
    "errors": 0,
    "files": 0,
    "reading": 0,
    "text": 0,
    "weapons": 0,
    "package_data": 0,
    "figures": 0,
    "__init__": 0,
    # data in, metrics out
    "esta": 1,
    "metrics": 1,
    "world": 2,
    "waypoints": 3,
    "sim": 4,
    # built on the simulator
    "replay": 5,
    "damage": 5,
    "synth": 5,
    "env": 5,
    "view": 5,  # the view page: reads what replay and evaluate write
    "evaluate": 6,
    "modeling": 6,  # the model tooling of `decoy train` and `decoy models`: above damage
    "bench": 6,
    "rl": 6,
    "commands": 7,
    "cli": 7,
    "entry": 8,  # the console script: loads the application
}


def _part(module: str) -> str:
    """The layer key of a module path relative to the package ("sim/engine.py" -> "sim")."""
    return module.split("/")[0].removesuffix(".py")


def _imports(path: Path) -> list[tuple[int, str]]:
    tree = ast.parse(path.read_text(), filename=str(path))
    found = []
    for node in ast.walk(tree):
        if isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
            names = [node.module]
        elif isinstance(node, ast.Import):
            names = [alias.name for alias in node.names]
        else:
            continue
        found += [(node.lineno, n) for n in names if n.startswith("decoy_cli.")]
    return found


def test_every_package_part_has_a_layer() -> None:
    parts = {_part(str(p.relative_to(PACKAGE))) for p in PACKAGE.rglob("*.py")}
    assert parts <= set(LAYERS), f"no layer for {sorted(parts - set(LAYERS))}"


def test_no_import_runs_up_the_layers() -> None:
    upward = []
    for path in sorted(PACKAGE.rglob("*.py")):
        own = _part(str(path.relative_to(PACKAGE)))
        for line, name in _imports(path):
            target = name.split(".")[1]
            if target != own and LAYERS[target] > LAYERS[own]:
                upward.append(f"{path.relative_to(PACKAGE)}:{line} imports {name}")
    assert upward == []


def test_a_lower_layer_imports_no_peer_it_depends_on_in_a_cycle() -> None:
    """Same-layer imports are allowed one way only: a pair of parts importing each other is a
    cycle."""
    edges: set[tuple[str, str]] = set()
    for path in PACKAGE.rglob("*.py"):
        own = _part(str(path.relative_to(PACKAGE)))
        for _, name in _imports(path):
            target = name.split(".")[1]
            if target != own and LAYERS[target] == LAYERS[own]:
                edges.add((own, target))
    assert sorted(e for e in edges if (e[1], e[0]) in edges) == []
