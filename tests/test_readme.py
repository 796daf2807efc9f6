"""The README's library example runs as written (on its first round, to stay fast)."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]


def test_the_library_example_runs(capsys: pytest.CaptureFixture[str], monkeypatch) -> None:
    text = (ROOT / "README.md").read_text()
    code = re.search(r"```python\n(.*?)```", text, re.S)
    assert code is not None, "the README has no python example"
    source = code.group(1)
    loop = 'iter_rounds(files, map_name="de_dust2")'
    assert loop in source
    monkeypatch.chdir(ROOT)
    exec(source.replace(loop, f"list({loop})[:1]"), {})
    printed = capsys.readouterr().out
    assert "mean_dist" in printed and printed.count("\n") == 11  # header + 10 players
