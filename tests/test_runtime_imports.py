"""Playing a round loads the damage models and nothing of the tooling that makes them: no module
of `decoy_cli.modeling` (samples, training, losses, scoring, fitting), none of which the
run-time package `decoy_cli.damage` may import.

Each check runs in a fresh interpreter, since this one has imported everything the other tests
use, and reads that interpreter's `sys.modules` after the run-time path has run."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
SAMPLE = ROOT / "examples" / "sample"

TOOLING = "decoy_cli.modeling"
"""The package the run-time path must not import (torch itself loads torch.optim on import)."""

REPORT = """
import json, sys
print(json.dumps(sorted(m for m in sys.modules if m.startswith("decoy_cli"))))
"""

COMBAT_STEP = """
import numpy as np
import decoy_cli.damage
from decoy_cli.damage import load_damage_model
from decoy_cli.sim.combat import make_batch
from decoy_cli.sim.sight import VisiblePairs
from decoy_cli.sim.state import Agents

agents = Agents.create(
    ["t", "ct"], ["T", "CT"], np.array([[0.0, 0.0, 0.0], [6.0, 1.0, 0.0]]), np.zeros(2),
    weapons=["AK-47", "M4A4"],
)
pairs = VisiblePairs(np.array([0, 1]), np.array([1, 0]))
for choice in ("rules", "shipped"):
    model = load_damage_model(choice)
    result = model(make_batch(agents, pairs, "de_dust2"), np.random.default_rng(0))
    assert len(result.damage) == 2
"""

REPLAY = f"""
from decoy_cli.damage import load_damage_model
from decoy_cli.esta import collect_match_files, read_match
from decoy_cli.replay import ReplayOptions, replay_round
from decoy_cli.waypoints.build import builtin_graph

files, _ = collect_match_files([{str(SAMPLE)!r}])
round_ = read_match(files[0]).rounds[0]
options = ReplayOptions(combat=True, bomb=True, damage_model=load_damage_model("rules"))
replay_round(round_, builtin_graph(), options)
"""


def _loaded(code: str) -> list[str]:
    """The decoy modules a fresh interpreter holds after running `code`."""
    done = subprocess.run(
        [sys.executable, "-c", code + REPORT],
        capture_output=True,
        text=True,
        cwd=ROOT,
        timeout=600,
        check=False,
    )
    assert done.returncode == 0, done.stderr[-2000:]
    return json.loads(done.stdout.strip().splitlines()[-1])


def test_a_combat_step_imports_no_modeling_module() -> None:
    loaded = _loaded(COMBAT_STEP)
    assert "decoy_cli.damage.rules_damage" in loaded and "decoy_cli.damage.combat" in loaded
    assert [m for m in loaded if m.startswith(TOOLING) or "train" in m] == []


@pytest.mark.skipif(not SAMPLE.is_dir(), reason="needs examples/sample")
def test_a_replay_with_shooting_imports_no_modeling_module() -> None:
    loaded = _loaded(REPLAY)
    assert "decoy_cli.damage.rules_damage" in loaded and "decoy_cli.replay" in loaded
    assert [m for m in loaded if m.startswith(TOOLING) or "train" in m] == []
