"""The studies' own code lives beside their scripts in benchmarks/studies/, outside the package;
a test of a study imports it from there (`study("_damage_rules")`)."""

from __future__ import annotations

import importlib
import sys
from pathlib import Path
from types import ModuleType

STUDIES = Path(__file__).resolve().parents[1] / "benchmarks" / "studies"


def study(name: str) -> ModuleType:
    """The module `name` of benchmarks/studies/ (its folder put on the path, as running one of
    its scripts does, so its sibling imports resolve)."""
    if str(STUDIES) not in sys.path:
        sys.path.insert(0, str(STUDIES))
    return importlib.import_module(name)
