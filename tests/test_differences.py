"""The rebuild tests' failure messages name what differs (tests/differences.py)."""

from __future__ import annotations

import json
import lzma
from pathlib import Path

import numpy as np
from differences import json_difference, npz_difference


def test_npz_difference_names_the_array_and_the_element(tmp_path: Path) -> None:
    np.savez(tmp_path / "a.npz", positions=np.zeros((3, 2)), kind=np.arange(4))
    changed = np.zeros((3, 2))
    changed[2, 1] = 0.5
    np.savez(tmp_path / "b.npz", positions=changed, kind=np.arange(4))
    message = npz_difference(tmp_path / "a.npz", tmp_path / "b.npz")
    assert message == "positions[2, 1]: built 0.0, shipped 0.5 (1 elements differ)"
    np.savez(tmp_path / "c.npz", positions=np.zeros((2, 2)), kind=np.arange(4))
    assert npz_difference(tmp_path / "a.npz", tmp_path / "c.npz") == (
        "positions: built float64(3, 2), shipped float64(2, 2)"
    )


def test_json_difference_names_the_path_and_both_values(tmp_path: Path) -> None:
    a = {"gameRounds": [{"roundNum": 1, "frames": [{"tick": 64}]}]}
    b = {"gameRounds": [{"roundNum": 1, "frames": [{"tick": 65}]}]}
    (tmp_path / "a.json.xz").write_bytes(lzma.compress(json.dumps(a).encode()))
    (tmp_path / "b.json").write_text(json.dumps(b))
    message = json_difference(tmp_path / "a.json.xz", tmp_path / "b.json")
    assert message == "$.gameRounds[0].frames[0].tick: built 64, shipped 65"
    (tmp_path / "c.json").write_text(json.dumps(a, indent=1))
    assert json_difference(tmp_path / "a.json.xz", tmp_path / "c.json") == (
        "the JSON is equal: the encoding or compression differs"
    )
