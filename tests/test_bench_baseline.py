"""`decoy bench --baseline`: the same sections on two code trees, alternating, as ratios."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest
from typer.testing import CliRunner

from decoy_cli.bench.baseline import Ratio, baseline_tree, current_tree, headlines
from decoy_cli.cli import app
from decoy_cli.errors import DecoyError

runner = CliRunner()
WIDE = {"COLUMNS": "200"}
CHECKOUT = Path(__file__).resolve().parents[1]
needs_git = pytest.mark.skipif(not (CHECKOUT / ".git").exists(), reason="needs a git checkout")


def test_ratios_pair_the_alternating_runs() -> None:
    ratio = Ratio("metrics", "pairs/s", [300.0, 330.0, 360.0], [100.0, 110.0, 90.0])
    row = ratio.to_dict()
    assert row["ratios"] == [3.0, 3.0, 4.0]
    assert (row["ratio_median"], row["ratio_min"], row["ratio_max"]) == (3.0, 3.0, 4.0)


def test_headlines_are_rates_higher_is_better() -> None:
    assert headlines("metrics", {"pairs_per_s": 10.0}) == {"pairs/s": 10.0}
    kinematic = {"agents": 10, "ticks_per_s": 3.0}
    assert headlines("kinematic", kinematic) == {"ticks/s, 10 agents": 3.0}
    arrays = "agent decisions/s, arrays (PettingZoo where absent)"
    assert headlines("env", {"decisions_per_s": 7.0}) == {"agent decisions/s": 7.0, arrays: 7.0}
    both = {"decisions_per_s": 7.0, "array_decisions_per_s": 9.0}
    assert headlines("env", both) == {"agent decisions/s": 7.0, arrays: 9.0}
    rows = [{"agents": 2, "ticks_per_s": 5.0}, {"agents": 10, "ticks_per_s": 2.0}]
    assert headlines("table1", {"rows": rows}) == {
        "ticks/s, 2 agents": 5.0,
        "ticks/s, 10 agents": 2.0,
    }
    step = {"layout": "spread", "parts": {"step": {"median_ms": 0.5}}}
    assert headlines("combat_step", {"rows": [step]}) == {"steps/s, spread": 2000.0}
    assert headlines("replay", {"error": "boom"}) == {}
    assert headlines("reader", {"files": 0}) == {}
    # an older baseline's result without a figure, or a zero time, gives no ratio, not a crash
    assert headlines("metrics", {"wall_s": 1.0}) == {}
    broken = {"layout": "spread", "parts": {"step": {"median_ms": 0.0}}}
    assert headlines("combat_step", {"rows": [broken]}) == {}


@needs_git
def test_a_git_ref_side_by_side_with_a_relative_out(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.chdir(tmp_path)
    args = ["bench", "--quick", "--sections", "metrics", "--repeats", "1", "--baseline", "HEAD"]
    result = runner.invoke(app, [*args, "--out", "side/bench.json"], env=WIDE)
    assert result.exit_code == 0, result.output
    assert "speed-up of the current code over HEAD" in result.output
    report = json.loads((tmp_path / "side" / "bench.json").read_text())["side_by_side"]
    (row,) = report["ratios"]
    assert row["section"] == "metrics" and len(row["current"]) == len(row["baseline"]) == 1
    assert row["current"][0] > 0 and row["baseline"][0] > 0
    runs = report["runs"]["metrics"]
    assert "/baseline-" in runs["baseline"][0]["code"]
    assert runs["current"][0]["code"].startswith(str(CHECKOUT))
    assert [p.name for p in (tmp_path / "side").iterdir()] == ["bench.json"]  # nothing left


@needs_git
def test_a_portable_section_runs_this_trees_file_on_the_baselines_package(tmp_path: Path) -> None:
    args = ["bench", "--quick", "--sections", "kinematic", "--repeats", "1", "--baseline", "HEAD"]
    result = runner.invoke(app, [*args, "--models", "none", "--out", str(tmp_path / "b.json")])
    assert result.exit_code == 0, result.output
    report = json.loads((tmp_path / "b.json").read_text())["side_by_side"]
    (row,) = report["ratios"]
    assert row["figure"] == "ticks/s, 10 agents" and row["baseline"][0] > 0
    runs = report["runs"]["kinematic"]
    assert "/baseline-" in runs["baseline"][0]["code"]
    assert not list(tmp_path.glob("**/.numba-cache"))  # removed with the baseline's tree
    assert runs["baseline"][0]["damage_model"] == "none"


def test_a_baseline_that_runs_the_current_code_is_an_error(tmp_path: Path) -> None:
    # This interpreter imports this very code: a "ratio" would be 1 and mean nothing.
    out = tmp_path / "bench.json"
    args = ["bench", "--quick", "--sections", "metrics", "--repeats", "1"]
    result = runner.invoke(app, [*args, "--baseline", sys.executable, "--out", str(out)], env=WIDE)
    assert result.exit_code != 0
    assert "error: the baseline ran the same code as the current side" in result.output
    assert list(tmp_path.iterdir()) == []


@needs_git
def test_a_git_ref_is_exported_beside_the_report_and_removed(tmp_path: Path) -> None:
    head = subprocess.run(
        ["git", "-C", str(CHECKOUT), "rev-parse", "HEAD"], capture_output=True, text=True
    ).stdout.strip()
    with baseline_tree("HEAD", tmp_path) as tree:
        assert tree.path is not None and tree.path.parent == tmp_path
        assert tree.path.name.startswith(f"baseline-{head[:12]}-")
        assert (tree.path / "decoy_cli" / "bench" / "baseline.py").is_file()
        assert tree.label == f"HEAD ({head[:12]})"
        assert tree.numba_cache == tree.path / ".numba-cache"  # its kernels go with it
    assert list(tmp_path.iterdir()) == []
    assert current_tree().path == CHECKOUT


@needs_git
def test_bad_baselines_and_sections_are_one_line(tmp_path: Path) -> None:
    unknown = pytest.raises(DecoyError, match="neither a commit of this checkout nor an executable")
    with unknown, baseline_tree("no-such-ref", tmp_path):
        pass
    out = str(tmp_path / "b.json")
    bad_ref = runner.invoke(app, ["bench", "--baseline", "no-such-ref", "--out", out], env=WIDE)
    assert bad_ref.exit_code != 0 and "error: --baseline no-such-ref" in bad_ref.output
    sections = runner.invoke(app, ["bench", "--sections", "metrics,warp", "--out", out], env=WIDE)
    assert sections.exit_code != 0
    assert "unknown warp" in sections.output and "table1" in sections.output
