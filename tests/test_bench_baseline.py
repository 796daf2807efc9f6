"""`decoy bench --baseline`: the same sections on two code trees, alternating, as ratios."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest
from typer.testing import CliRunner

from decoy_cli.bench import BenchConfig
from decoy_cli.bench.baseline import (
    Ratio,
    baseline_tree,
    current_tree,
    headlines,
    run_args,
    run_in,
)
from decoy_cli.cli import app
from decoy_cli.damage.choice import ModelName
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
    step = {"agents": 10, "layout": "spread", "parts": {"step": {"median_ms": 0.5}}}
    crowd = {"agents": 100, "layout": "spread", "parts": {"step": {"median_ms": 4.0}}}
    assert headlines("combat_step", {"rows": [step, crowd]}) == {
        "steps/s, 10 agents, spread": 2000.0,
        "steps/s, 100 agents, spread": 250.0,
    }
    kernel = {"kernel": "dtw", "size": "310x310", "median_ms": 0.25}
    assert headlines("metrics", {"pairs_per_s": 10.0, "kernels": [kernel]}) == {
        "pairs/s": 10.0,
        "calls/s, dtw 310x310": 4000.0,
    }
    assert headlines("replay", {"error": "boom"}) == {}
    assert headlines("reader", {"files": 0}) == {}
    # an older baseline's result without a figure, or a zero time, gives no ratio, not a crash
    assert headlines("metrics", {"wall_s": 1.0}) == {}
    broken = {"layout": "spread", "parts": {"step": {"median_ms": 0.0}}}
    assert headlines("combat_step", {"rows": [broken]}) == {}


@needs_git
def test_a_git_ref_runs_this_trees_portable_section_on_its_package(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """The combat step, the portable section whose compiled code a baseline's tree compiles
    quickest: every portable section runs through the same driver."""
    monkeypatch.chdir(tmp_path)  # and a relative --out
    args = ["bench", "--quick", "--sections", "combat_step", "--repeats", "1"]
    out = ["--combat-agents", "2", "--baseline", "HEAD", "--models", "none"]
    result = runner.invoke(app, [*args, *out, "--out", "side/bench.json"], env=WIDE)
    assert result.exit_code == 0, result.output
    assert "speed-up of the current code over HEAD" in result.output
    report = json.loads((tmp_path / "side" / "bench.json").read_text())["side_by_side"]
    figures = [(row["section"], row["figure"]) for row in report["ratios"]]
    assert figures == [
        ("combat_step", "steps/s, 2 agents, spread"),
        ("combat_step", "steps/s, 2 agents, clustered"),
    ]
    for row in report["ratios"]:
        assert len(row["current"]) == len(row["baseline"]) == 1
        assert row["current"][0] > 0 and row["baseline"][0] > 0
    runs = report["runs"]["combat_step"]
    (baseline,) = runs["baseline"]
    assert "/baseline-" in baseline["code"]
    assert runs["current"][0]["code"].startswith(str(CHECKOUT))
    assert [p.name for p in (tmp_path / "side").iterdir()] == ["bench.json"]  # nothing left
    assert not list(tmp_path.glob("**/.numba-cache"))  # removed with the baseline's tree
    assert baseline["damage_model"] == "none"
    # the current code's sizes, on either side
    assert [row["agents"] for row in baseline["rows"]] == [2, 2]


def test_either_tree_is_asked_only_what_it_supports(tmp_path: Path) -> None:
    folder = tmp_path / "models"
    config = BenchConfig.create(quick=True, models=ModelName.NONE)
    run = run_args(config)
    assert "map_name" not in run["switches"] and "map" not in run["portable"]
    assert run["sizes"] == {"agent_counts": [2, 10], "decisions": 1000}
    assert run["portable"]["combat_agents"] == [10] and run["portable"]["decisions"] == 1000
    elsewhere = BenchConfig.create(quick=True, models=str(folder), map_name="mirage")
    run = run_args(elsewhere)
    assert run["switches"]["map_name"] == run["portable"]["map"] == "de_mirage"
    assert run["switches"]["models"] == run["portable"]["models"] == str(folder.resolve())


def test_the_driver_sets_table_1_sizes_and_refuses_a_size_the_tree_lacks(tmp_path: Path) -> None:
    config = BenchConfig.create(quick=True, models=ModelName.NONE, agent_counts=[3], decisions=60)
    run = run_args(config)
    result = run_in(current_tree(), "table1", run, None, tmp_path)
    assert [row["agents"] for row in result["rows"]] == [3]
    assert result["decisions_per_row"] == 60
    lacking = {**run, "sizes": {**run["sizes"], "combat_width": 3}}
    refused = run_in(current_tree(), "table1", lacking, None, tmp_path)
    assert "BenchConfig has no combat_width" in refused["error"]
    assert list(tmp_path.iterdir()) == []


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
