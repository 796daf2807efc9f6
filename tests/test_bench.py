"""`decoy bench --quick` end to end, and the parts of the benchmark that can go wrong alone.

The end-to-end run measures on a generated fixture match (`--data`), with a model folder that
does not exist, so the fallback to line of sight without inference is exercised and must be
labelled. The learned model path runs one combat-step section in-process on a model folder of
freshly initialised networks. Nothing here asserts a speed.
"""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from esta_fixtures import write_match
from typer.testing import CliRunner

from decoy_cli.bench import (
    SECTIONS,
    BenchConfig,
    ModelStatus,
    check_damage_model,
    find_data,
    run_isolated,
    run_section,
)
from decoy_cli.bench.machine import cpu_model, memory_gb, peak_rss_mb, ru_maxrss_mb
from decoy_cli.bench.simspeed import PAPER_TICKS_PER_S, NeverHits
from decoy_cli.cli import app
from decoy_cli.damage.choice import ModelName
from decoy_cli.errors import DecoyError, EstaError
from decoy_cli.replay import ReplayOptions
from decoy_cli.sim.combat import VisiblePairs, make_batch
from decoy_cli.sim.setup import RoundSetup, RunSpec, SetupError
from decoy_cli.waypoints.build import builtin_graph

runner = CliRunner()
WIDE = {"COLUMNS": "220"}


@pytest.fixture(scope="module")
def quick_run(tmp_path_factory: pytest.TempPathFactory) -> tuple[Any, dict[str, Any]]:
    """One `decoy bench --quick` on a fixture match with an unloadable model folder, at sizes
    given in place of the quick ones (Table 1's agent counts, each once, and decisions; the
    combat step's agent counts): what the options give must reach every section."""
    folder = tmp_path_factory.mktemp("bench")
    data = folder / "data"
    data.mkdir()
    write_match(data / "fixture.json.xz")
    out = folder / "out" / "bench.json"
    result = runner.invoke(
        app,
        [
            "bench",
            "--quick",
            *("--agents", "2,4,2", "--decisions", "150", "--combat-agents", "2,12"),
            "--data",
            str(data),
            "--models",
            str(folder / "no-such-models"),
            "--out",
            str(out),
        ],
        env=WIDE,
    )
    assert result.exit_code == 0, result.output
    return result, json.loads(out.read_text())


def test_quick_bench_writes_every_section_and_the_machine(quick_run) -> None:
    result, report = quick_run
    assert set(report["sections"]) == set(SECTIONS)
    for name, section in report["sections"].items():
        assert "error" not in section and "skipped" not in section, name
        assert section["peak_rss_mb"] > 0 and section["ru_maxrss_mb"] > 0
    machine = report["machine"]
    assert machine["cores"] >= 1 and machine["cpu"]
    assert machine["python"] and machine["packages"]["numpy"] == np.__version__
    assert "torch" in machine["packages"]
    assert report["quick"] is True and report["data"]["kind"] == "given"
    assert "machine:" in result.stdout and machine["cpu"] in result.stdout
    for title in ("Table 1", "kinematic core", "PettingZoo", "combat step", "replay", "reader"):
        assert title in result.stdout


def test_the_model_fallback_is_said_and_labelled(quick_run) -> None:
    result, report = quick_run
    model = report["damage_model"]
    assert model["loaded"] is False and "no-such-models" in model["error"]
    assert "could not be loaded" in result.stdout
    assert "line of sight only, no inference" in report["sections"]["table1"]["damage_model"]
    assert report["sections"]["replay"]["options"]["combat"] is False
    for name in ("kinematic", "env", "combat_step"):  # the portable sections name their model
        assert "no-such-models did not load" in report["sections"][name]["damage_model"]


def test_table1_rows_are_consistent(quick_run) -> None:
    _, report = quick_run
    assert report["config"]["agent_counts"] == [2, 4] and report["config"]["decisions"] == 150
    table = report["sections"]["table1"]
    assert [row["agents"] for row in table["rows"]] == [2, 4]
    for row in table["rows"]:
        assert 1000 > row["decisions"] >= table["decisions_per_row"] == 150
        assert row["ticks"] > 0 and row["rounds"] >= 1
        assert math.isclose(row["game_s"], row["ticks"] / 60)
        assert math.isclose(row["ticks_per_s"], row["ticks"] / row["wall_s"])
        assert math.isclose(row["time_scale"], row["game_s"] / row["wall_s"])
        assert row["paper_ticks_per_s"] == PAPER_TICKS_PER_S.get(row["agents"])
        assert "ratio_to_paper" not in row  # the paper's machine is not this one


def test_throughput_sections_count_what_they_measured(quick_run) -> None:
    _, report = quick_run
    sections = report["sections"]
    kinematic = sections["kinematic"]
    assert kinematic["agents"] == 10 and 150 <= kinematic["decisions"] < 1000
    assert kinematic["ticks_per_s"] == pytest.approx(kinematic["ticks"] / kinematic["wall_s"])
    env = sections["env"]
    assert env["rounds"] == 1 and len(env["outcomes"]) == 1 and env["outcomes"][0]
    assert env["decisions"] >= env["steps"] > 0 and env["game_s"] > 0
    assert env["decisions_per_s"] == pytest.approx(env["decisions"] / env["wall_s"])
    replay = sections["replay"]
    # the fixture has rounds 1 and 2 with frames (one replayed untimed to warm up), 3 without
    assert replay["rounds"] == 1 and replay["failed"] == 1
    assert "no frames" in replay["failures"][0]
    assert replay["rounds_per_s"] == pytest.approx(1 / replay["wall_s"])
    reader = sections["reader"]
    assert reader["files"] == 1 and reader["rounds"] == 3
    assert reader["mb_per_s_decompressed"] > reader["mb_per_s_compressed"] > 0
    metrics = sections["metrics"]
    assert metrics["pairs"] == 100 and metrics["evaluated"] == 100
    kernels = [(row["kernel"], row["size"]) for row in metrics["kernels"]]
    assert kernels == [
        (kernel, size)
        for size in ("310x310", "451x451")
        for kernel in ("dtw", "frechet", "frechet x-y")
    ]
    for row in metrics["kernels"]:
        assert row["calls"] == 50 and row["max_ms"] >= row["median_ms"] >= row["min_ms"] > 0
    rows = sections["combat_step"]["rows"]
    shapes = [(row["agents"], row["layout"], row["steps"]) for row in rows]
    # 20 quick steps at 10 agents or fewer; proportionally fewer above: 20 * 10 // 12
    assert shapes == [
        (2, "spread", 20),
        (2, "clustered", 20),
        (12, "spread", 16),
        (12, "clustered", 16),
    ]
    for row in rows:
        parts = row["parts"]
        assert parts["step"]["median_ms"] >= parts["visible_pairs"]["median_ms"] > 0


@pytest.mark.parametrize(
    ("option", "value", "message"),
    [
        ("--agents", "1", "--agents 1: Table 1 plays 2 to "),
        ("--agents", "2,100000", "--agents 100000: Table 1 plays 2 to "),
        ("--agents", "2,x", "--agents '2,x': give whole numbers separated by commas"),
        ("--agents", ",", "--agents ',': give whole numbers"),
        ("--combat-agents", "7", "--combat-agents 7: give an even count from 2 to"),
        ("--combat-agents", "0", "--combat-agents 0: give an even count"),
        ("--decisions", "0", "Invalid value for '--decisions'"),
    ],
)
def test_bad_sizes_are_one_line_before_any_section(option: str, value: str, message: str) -> None:
    result = runner.invoke(app, ["bench", "--quick", option, value], env=WIDE)
    assert result.exit_code != 0
    assert result.stderr.startswith(f"error: {message}") and result.stderr.count("\n") == 1
    assert "Table 1" not in result.stdout


def test_given_sizes_replace_the_quick_ones_and_no_other() -> None:
    quick = BenchConfig.create(quick=True, models=ModelName.NONE)
    sized = BenchConfig.create(
        quick=True, models=ModelName.NONE, agent_counts=[6, 2, 6], decisions=7, combat_agents=[100]
    )
    assert (sized.agent_counts, sized.decisions, sized.combat_agents) == ((6, 2), 7, (100,))
    assert (quick.agent_counts, quick.decisions, quick.combat_agents) == ((2, 10), 1000, (10,))
    assert sized.combat_repeats == quick.combat_repeats == 20
    assert sized.metric_pairs == quick.metric_pairs
    with pytest.raises(DecoyError, match="--decisions 0"):
        BenchConfig.create(quick=False, models=ModelName.NONE, decisions=0)
    graph = builtin_graph()  # n // 2 T and the rest CT, each on a waypoint of its spawn
    room = min(2 * len(graph.region_of("t_spawn")) + 1, 2 * len(graph.region_of("ct_spawn")))
    assert BenchConfig.create(quick=True, models="none", agent_counts=[room]).agent_counts == (
        room,
    )
    with pytest.raises(DecoyError, match=f"--agents {room + 1}: Table 1 plays 2 to {room} "):
        BenchConfig.create(quick=True, models="none", agent_counts=[room + 1])


def test_find_data_prefers_the_given_folder_then_the_candidates(tmp_path: Path) -> None:
    empty, real, sample = (tmp_path / name for name in ("empty", "real", "sample"))
    for folder in (empty, real, sample):
        folder.mkdir()
    write_match(sample / "m.json.xz")
    candidates = (("real", real), ("missing", tmp_path / "nope"), ("synthetic sample", sample))
    found = find_data(None, candidates)
    assert found is not None and found.kind == "synthetic sample"
    assert found.files == [sample / "m.json.xz"]
    assert find_data(None, candidates[:2]) is None
    assert find_data(sample, ()).kind == "given"
    with pytest.raises(EstaError, match="no match files in this folder"):
        find_data(empty, candidates)


def test_without_data_the_data_sections_are_skipped_with_the_reason() -> None:
    config = BenchConfig.create(quick=True, models="none")
    status = check_damage_model("none")
    assert not status.loaded and "--models none" in status.label
    for name in ("replay", "reader"):
        skipped = run_isolated(name, config, status, None)
        assert "examples/sample" in skipped["skipped"]


def test_a_failing_section_is_an_error_entry_not_a_crash() -> None:
    config = BenchConfig.create(quick=True, models="/no/such/folder")
    status = ModelStatus("/no/such/folder", loaded=True, label="pretend")
    result = run_isolated("table1", config, status, None)
    assert "no such model folder" in result["error"]


def test_bad_options_are_one_line(tmp_path: Path) -> None:
    mover = runner.invoke(app, ["bench", "--quick", "--mover", "warp"], env=WIDE)
    assert mover.exit_code == 2 and mover.stderr.count("\n") == 1
    assert mover.stderr.startswith("error: Invalid value for '--mover': ")
    assert "'warp' is not one of 'kinematic', 'physics'" in mover.stderr
    blocker = tmp_path / "a-file"
    blocker.write_text("")
    unwritable = runner.invoke(
        app, ["bench", "--quick", "--out", str(blocker / "bench.json")], env=WIDE
    )
    assert unwritable.exit_code == 1 and unwritable.stderr.startswith(
        f"error: cannot write {blocker / 'bench.json'}: "
    )
    assert "Table 1" not in unwritable.stdout  # refused before any section ran
    folder = runner.invoke(app, ["bench", "--quick", "--out", str(tmp_path)], env=WIDE)
    assert folder.exit_code == 1 and "is a folder" in folder.stderr
    data = runner.invoke(app, ["bench", "--quick", "--data", str(tmp_path)], env=WIDE)
    assert data.exit_code == 1 and "no match files in this folder" in data.stderr
    with pytest.raises(DecoyError, match="unknown mover 'teleport'"):  # the library's one check
        RoundSetup(graph=builtin_graph(), mover="teleport")  # type: ignore[arg-type]


@pytest.mark.parametrize(
    "make",
    [
        lambda: RunSpec(mover="teleport"),
        lambda: ReplayOptions(mover="teleport", combat=False),
        lambda: BenchConfig.create(quick=True, models=ModelName.NONE, mover="teleport"),
    ],
)
def test_every_runs_options_refuse_an_unknown_mover_by_the_one_check(make: Any) -> None:
    """The replay's, the benchmark's and the plain run spec share the switches (`Switches`),
    and with them the one check of the mover."""
    with pytest.raises(SetupError, match="unknown mover 'teleport' \\(use kinematic or physics\\)"):
        make()


def test_a_learned_model_runs_in_the_combat_step(tmp_path: Path) -> None:
    torch = pytest.importorskip("torch")
    from decoy_cli.damage.features import PAPER_SPEC
    from decoy_cli.damage.model_folder import save_dip, save_dog
    from decoy_cli.damage.networks import DipNet, DogNet

    torch.manual_seed(0)
    save_dip(tmp_path, DipNet(), PAPER_SPEC, threshold=0.0)  # every visible armed pair hits
    save_dog(tmp_path, DogNet(), PAPER_SPEC)
    status = check_damage_model(str(tmp_path))
    assert status.loaded and status.error is None and str(tmp_path) in status.label
    config = BenchConfig.create(quick=True, models=str(tmp_path))
    result = run_section("combat_step", config, status, None)
    assert result["damage_model"] == str(tmp_path)  # loaded: named as given
    clustered = result["rows"][1]
    assert clustered["visible_pairs_median"] > 0
    assert clustered["parts"]["model"]["median_ms"] > 0


def test_never_hits_and_the_machine_helpers(tmp_path: Path) -> None:
    from decoy_cli.bench.combat import random_agents
    from decoy_cli.waypoints.build import builtin_graph

    rng = np.random.default_rng(0)
    agents = random_agents(builtin_graph(), 2, False, rng)
    pairs = VisiblePairs(np.array([0, 2]), np.array([2, 0]))
    hit = NeverHits()(make_batch(agents, pairs, "de_dust2"), rng)
    assert not hit.hit.any() and (hit.damage == 0).all()
    cpuinfo = tmp_path / "cpuinfo"
    cpuinfo.write_text("processor\t: 0\nmodel name\t: Test CPU 9000\n")
    assert cpu_model(cpuinfo) == "Test CPU 9000"
    assert cpu_model(tmp_path / "missing")  # falls back to platform
    meminfo = tmp_path / "meminfo"
    meminfo.write_text("MemTotal:        2048000 kB\nMemFree: 1 kB\n")
    assert memory_gb(meminfo) == pytest.approx(2048000 * 1024 / 1e9)
    assert memory_gb(tmp_path / "missing") is None
    status = tmp_path / "status"
    status.write_text("Name: python\nVmPeak: 9 kB\nVmHWM:\t  51200 kB\nVmRSS: 1 kB\n")
    assert peak_rss_mb(status) == pytest.approx(51200 * 1024 / 1e6)
    assert peak_rss_mb(tmp_path / "missing") >= ru_maxrss_mb() > 1


def test_a_table_1_row_and_its_record_name_the_same_fields() -> None:
    """`SpeedRow.to_dict` hands its fields over as they are: the record must name them all."""
    from dataclasses import fields

    from decoy_cli.bench.records import SpeedRowRecord
    from decoy_cli.bench.simspeed import SpeedRow

    assert list(SpeedRowRecord.__annotations__) == [f.name for f in fields(SpeedRow)]
