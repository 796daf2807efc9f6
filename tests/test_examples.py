"""The examples run as their docstrings say (one short round each)."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def test_random_agents_plays_a_round_to_its_end() -> None:
    script = ROOT / "examples" / "random_agents.py"
    done = subprocess.run(
        [sys.executable, str(script), "--rounds", "1", "--models", "none"],
        capture_output=True,
        text=True,
        timeout=300,
        cwd=ROOT,
    )
    assert done.returncode == 0, done.stderr
    header, row = done.stdout.strip().splitlines()[-2:]
    assert header.split()[:3] == ["round", "winner", "reason"]
    # nobody shoots without a model: the round ends by the bomb or the clock
    assert row.split()[0] == "1" and row.split()[2] in ("TargetSaved", "TargetBombed")
