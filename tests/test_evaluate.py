"""`decoy evaluate`: the parallel batch, its cache and resume, bad input, outputs, Dask.

Matches are tests/esta_fixtures.py documents whose 5 T and 4 CT players walk shortest paths of
the shipped de_dust2 graph (two waypoints per data frame) from the T spawn and the CT spawn;
round 3 (no frames) is dropped from the clean files, so each clean match has 2 rounds. Runs
through the library share one two-worker local pool; a reference run uses one worker, and the
other runs (two workers, resumed, Dask) must give exactly its numbers.
"""

from __future__ import annotations

import json
import lzma
import os
import re
import sys
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd
import pytest
from esta_fixtures import make_match, write_match
from typer.testing import CliRunner

from decoy_cli.cli import app
from decoy_cli.csgo import HAMMER_TO_M
from decoy_cli.errors import DecoyError, OutputError
from decoy_cli.evaluate.backends import DaskBackend, InProcessBackend, LocalBackend
from decoy_cli.evaluate.cache import RunCache
from decoy_cli.evaluate.heat import HeatGrid, grid_sums, read_grid_sums
from decoy_cli.evaluate.job import RoundTask, evaluate_round, is_synthetic
from decoy_cli.evaluate.outputs import FAILURE_COLUMNS
from decoy_cli.evaluate.runner import Evaluation, ProgressEvent, make_settings, run_evaluation
from decoy_cli.evaluate.settings import EvalSettings, round_key
from decoy_cli.evaluate.tables import Tables, build_tables, hp_metrics_from_sums
from decoy_cli.metrics import FASTDTW_METRIC, METRIC_NAMES, hp_metrics
from decoy_cli.metrics.hp_sums import hp_stats
from decoy_cli.waypoints.build import GRAPH_FILE, builtin_graph
from decoy_cli.waypoints.places import PlaceFinder
from decoy_cli.world.navmesh import asset_dir

DATA = Path(__file__).resolve().parents[1].parent / "shared" / "data"
TSIDE = DATA / "esta_dust2_tside"

runner = CliRunner()
WIDE = {"COLUMNS": "220"}
PNG = b"\x89PNG\r\n\x1a\n"
NAMES = ["t1", "t2", "t3", "t4", "BOT t5", "ct1", "ct2", "ct3", "ct4"]
CLEAN_ROUNDS = 4  # two clean matches of two rounds


def _paths(count: int, region: str, offset: int) -> list[list[int]]:
    """`count` shortest paths of the graph leaving `region`, each about 15 m long."""
    graph = builtin_graph()
    nodes = graph.region_of(region)
    paths = []
    for i in range(count):
        start = int(nodes[(53 * i + offset) % len(nodes)])
        dist, _ = graph.path_lengths(start)
        goal = int(np.argmin(np.abs(np.where(np.isfinite(dist), dist, np.inf) - 15.0)))
        paths.append(graph.shortest_path(start, goal))
    return paths


def walking_match(match_id: str, offset: int, *, keep_round3: bool = False) -> dict[str, Any]:
    """The fixture match with every player on the graph (see the module docstring)."""
    document = make_match()
    document["matchID"] = match_id
    if not keep_round3:
        document["gameRounds"] = document["gameRounds"][:2]
    positions = builtin_graph().positions
    walks = _paths(5, "t_spawn", offset) + _paths(4, "ct_spawn", offset)
    for round_ in document["gameRounds"][:2]:
        for j, frame in enumerate(round_["frames"]):
            for team in ("t", "ct"):
                for player in frame[team]["players"]:
                    walk = walks[NAMES.index(player["name"])]
                    x, y, z = positions[walk[min(2 * j, len(walk) - 1)]] / HAMMER_TO_M
                    player.update(x=x, y=y, z=z)
    return document


@pytest.fixture(scope="module")
def clean(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A folder of two clean matches (4 rounds), one xz, one plain JSON."""
    folder = tmp_path_factory.mktemp("clean")
    write_match(folder / "a.json.xz", walking_match("match-a", 0))
    write_match(folder / "b.json", walking_match("match-b", 11))
    return folder


@pytest.fixture(scope="module")
def settings() -> EvalSettings:
    return make_settings(
        map_name="dust2", combat=False, bomb=False, models="shipped", mover="kinematic", seed=0
    )


@pytest.fixture(scope="module")
def pool() -> Iterator[LocalBackend]:
    with LocalBackend(2) as backend:
        yield backend


@pytest.fixture(scope="module")
def reference(
    clean: Path, settings: EvalSettings, tmp_path_factory: pytest.TempPathFactory
) -> tuple[Evaluation, Tables]:
    """The clean folder evaluated by one worker process."""
    with LocalBackend(1) as backend:
        evaluation = run_evaluation([clean], settings, tmp_path_factory.mktemp("ref"), backend)
    return evaluation, build_tables(evaluation.accumulator)


def assert_same_results(evaluation: Evaluation, reference: tuple[Evaluation, Tables]) -> None:
    """Every number of `evaluation` equals the reference run's (wall times aside)."""
    ref_evaluation, ref_tables = reference
    tables = build_tables(evaluation.accumulator)
    pd.testing.assert_frame_equal(tables.players, ref_tables.players)
    pd.testing.assert_frame_equal(
        tables.rounds.drop(columns="wall_seconds"),
        ref_tables.rounds.drop(columns="wall_seconds"),
    )
    for name in ("trajectory", "combat", "hp_curve", "places"):
        pd.testing.assert_frame_equal(getattr(tables, name), getattr(ref_tables, name))
    ref_acc, acc = ref_evaluation.accumulator, evaluation.accumulator
    assert np.array_equal(acc.heat_original, ref_acc.heat_original)
    assert np.array_equal(acc.heat_replay, ref_acc.heat_replay)
    assert acc.hp_pooled == ref_acc.hp_pooled


def _invoke(*args: str):
    return runner.invoke(app, ["evaluate", *args], env=WIDE)


# ---- the reference run and the CLI end to end ---------------------------------------------------


def test_the_reference_run_evaluates_every_player_round(
    reference: tuple[Evaluation, Tables],
) -> None:
    evaluation, tables = reference
    assert not evaluation.failures
    assert (evaluation.computed, evaluation.cached) == (CLEAN_ROUNDS, 0)
    assert len(tables.rounds) == CLEAN_ROUNDS and len(tables.players) == CLEAN_ROUNDS * 9
    evaluated = tables.players[tables.players["reason"].isna()]
    assert len(evaluated) >= CLEAN_ROUNDS * 8
    assert np.isfinite(evaluated[list(METRIC_NAMES)].to_numpy(float)).all()
    # players walk waypoints: the replay follows them within a few metres
    assert evaluated["mean_dist"].max() < 3.0
    # t3 dies in round 1 of each match: scripted at the data's frame, the simulator's tick
    # before it (the frame shows him dead), so within two 60 Hz ticks of the same time
    t3 = tables.players[(tables.players["player"] == "t3") & (tables.players["round"] == 1)]
    gap = (t3["death_time_original_s"] - t3["death_time_replay_s"]).abs()
    assert len(t3) == 2 and (gap < 2 / 60).all()
    assert tables.deaths.counts["died_both"] == 2
    # the winners are recorded (both teams in the data): outcome agreement is defined
    assert tables.rounds_with_winner == CLEAN_ROUNDS == tables.rounds_both_teams
    assert tables.outcome is not None
    assert int(tables.outcome.winner_confusion.to_numpy().sum()) == CLEAN_ROUNDS
    # every alive sample lands on the heat grid and in a place count
    acc = evaluation.accumulator
    assert acc.heat_original.sum() == tables.players["frames_original"].sum()
    assert acc.heat_replay.sum() == tables.players["frames_replay"].sum()
    assert acc.places_original.sum() == acc.heat_original.sum()
    # the error map pools the clock protocol's per-frame distances (to the millimetre)
    players = tables.players
    both = players["frames_original"].clip(upper=players["frames_replay"])  # here: equal
    pooled = (players["mean_dist"] * both).sum() / both.sum()
    assert acc.error_count.sum() == both.sum() == acc.places_error_count.sum()
    assert acc.error_mm.sum() / 1000 / acc.error_count.sum() == pytest.approx(pooled, abs=5e-4)


NO_FIGURES_RUN = ["evaluate", "--no-combat", "--no-bomb", "--no-figures"]
"""An evaluation whose test reads the tables only."""


def test_in_this_process_the_results_are_the_worker_s(
    clean: Path, settings: EvalSettings, reference: tuple[Evaluation, Tables], tmp_path: Path
) -> None:
    """`--workers 0` (`InProcessBackend`): the same numbers as a worker process, and the
    command says where the rounds ran; `DECOY_WORKERS` is the default a `--workers` overrides."""
    evaluation = run_evaluation([clean], settings, tmp_path / "lib", InProcessBackend())
    assert_same_results(evaluation, reference)
    out = tmp_path / "cli"
    result = runner.invoke(
        app,
        [*NO_FIGURES_RUN, str(clean), "--out", str(out)],
        env={**WIDE, "DECOY_WORKERS": "0"},
    )
    assert result.exit_code == 0, result.output
    assert "evaluating with this process" in result.output
    assert (out / "players.csv").read_text() == reference[1].players.to_csv(index=False)
    told = runner.invoke(
        app,
        [*NO_FIGURES_RUN, str(clean), "--workers", "1", "--out", str(out)],
        env={**WIDE, "DECOY_WORKERS": "0"},
    )
    assert told.exit_code == 0 and "evaluating with 1 local worker process" in told.output


def test_cli_end_to_end_writes_every_table_and_figure_with_two_workers(
    clean: Path, reference: tuple[Evaluation, Tables], tmp_path: Path
) -> None:
    out = tmp_path / "out"
    result = _invoke(str(clean), "--no-combat", "--no-bomb", "--workers", "2", "--out", str(out))
    assert result.exit_code == 0, result.output
    for text in ("protocol clock", "protocol paper", "paper_dtw", "HP, deaths and outcomes"):
        assert text in result.output
    assert "data: real" in result.output
    # the HP and death numbers say, in the terminal as in the report, what they do not measure
    assert "Combat was off: HP changes only" in result.output
    # the same numbers as one worker, down to the last digit of the CSV
    assert (out / "players.csv").read_text() == reference[1].players.to_csv(index=False)
    report = (out / "report.md").read_text()
    assert "| frame rate of the data | 2 frames/s |" in report
    assert (pd.read_csv(out / "rounds.csv")["frame_rate"] == 2.0).all()
    for heading in (
        "## What was run",
        "### Protocol clock",
        "### Protocol paper",
        "## HP, deaths and outcomes\n\nCombat was off: HP changes only",
        "Confusion of the winner",
        "Confusion of the end reason",
        "## Failures",
    ):
        assert heading in report
    for block in re.findall(r"(?:^\|.*\|\n)+", report, flags=re.MULTILINE):
        widths = {line.count(" | ") for line in block.splitlines() if not line.startswith("|-")}
        assert len(widths) == 1, block  # every row of a table has its header's columns
    links = re.findall(r"!\[[^\]]*\]\(([^)]+)\)", report)
    assert sorted(links) == sorted(
        f"figures/{name}.png"
        for name in ("heatmaps", "error_map", "hp_over_time", "death_times", "outcomes")
    )
    for link in links:
        assert (out / link).read_bytes().startswith(PNG)
    for name in (
        "trajectory",
        "unevaluated",
        "combat",
        "death_counts",
        "outcome_winner_confusion",
        "outcome_reason_confusion",
        "hp_over_time",
        "places",
    ):
        assert (out / "tables" / f"{name}.csv").is_file()
    for metric in METRIC_NAMES:
        assert f"`{metric}`" in report
    summary = json.loads((out / "summary.json").read_text())
    assert summary["data"] == "real"
    assert summary["counts"]["rounds_evaluated"] == CLEAN_ROUNDS
    assert summary["options"]["combat"] is False
    trajectory = pd.read_csv(out / "tables" / "trajectory.csv")
    paper_t = trajectory[(trajectory["group"] == "T") & (trajectory["metric"] == "paper_dtw")]
    assert paper_t["paper_mean"].item() == 0.873
    # the paper's Table 2 setting computes the paper's own FastDTW beside the exact DTW
    fast_t = trajectory[(trajectory["group"] == "T") & (trajectory["metric"] == FASTDTW_METRIC)]
    assert fast_t["paper_mean"].item() == 0.873 and fast_t["mean"].item() > 0
    assert "--fastdtw" in summary["command"]
    assert f"`{FASTDTW_METRIC}` is the paper's own computation" in report
    assert list(pd.read_csv(out / "failures.csv").columns) == list(FAILURE_COLUMNS)


# ---- cache and resume ---------------------------------------------------------------------------


class Interrupt:
    """A progress callback that presses Ctrl-C after `after` finished rounds."""

    def __init__(self, after: int) -> None:
        self.after = after

    def __call__(self, event: ProgressEvent) -> None:
        if event.stage == "rounds" and event.done >= self.after:
            raise KeyboardInterrupt


def test_an_interrupted_run_resumes_with_only_the_rest(
    clean: Path,
    settings: EvalSettings,
    pool: LocalBackend,
    reference: tuple[Evaluation, Tables],
    tmp_path: Path,
) -> None:
    with pytest.raises(KeyboardInterrupt):
        run_evaluation([clean], settings, tmp_path, pool, on_progress=Interrupt(1))
    assert len(list((tmp_path / "cache" / "rounds").glob("*.msgpack"))) == 1
    resumed = run_evaluation([clean], settings, tmp_path, pool)
    assert (resumed.cached, resumed.computed) == (1, CLEAN_ROUNDS - 1)
    assert_same_results(resumed, reference)
    again = run_evaluation([clean], settings, tmp_path, pool)
    assert (again.cached, again.computed) == (CLEAN_ROUNDS, 0)
    assert_same_results(again, reference)

    # another option is another result: nothing is reused
    other = make_settings(
        map_name="dust2", combat=False, bomb=False, models="shipped", mover="kinematic", seed=1
    )
    assert run_evaluation([clean], other, tmp_path, pool).computed == CLEAN_ROUNDS


def test_a_damaged_cache_file_is_computed_again(
    clean: Path,
    settings: EvalSettings,
    pool: LocalBackend,
    reference: tuple[Evaluation, Tables],
    tmp_path: Path,
) -> None:
    run_evaluation([clean], settings, tmp_path, pool)
    victim = sorted((tmp_path / "cache" / "rounds").glob("*.msgpack"))[0]
    victim.write_bytes(victim.read_bytes()[:50])
    rerun = run_evaluation([clean], settings, tmp_path, pool)
    assert (rerun.cached, rerun.computed) == (CLEAN_ROUNDS - 1, 1)
    assert RunCache(tmp_path).load_round(victim.stem) is not None  # readable again
    assert_same_results(rerun, reference)  # and computed to the same numbers


def test_a_sample_is_fixed_by_its_seed_not_by_the_paths(
    clean: Path, settings: EvalSettings, pool: LocalBackend, tmp_path: Path
) -> None:
    files = sorted(clean.iterdir())
    first = run_evaluation(files, settings, tmp_path / "one", pool, sample=2)
    second = run_evaluation(files[::-1], settings, tmp_path / "two", pool, sample=2)
    chosen = first.accumulator.round_rows()[["match", "round"]]
    assert len(chosen) == 2 and first.rounds_available == CLEAN_ROUNDS
    pd.testing.assert_frame_equal(chosen, second.accumulator.round_rows()[["match", "round"]])


# ---- bad input ----------------------------------------------------------------------------------


def crashing_job(task: RoundTask) -> Any:
    """The round job, but the worker dies on round 2 of any file named crashy*."""
    if task.round_num == 2 and Path(task.file).name.startswith("crashy"):
        os._exit(3)
    return evaluate_round(task)


def test_workers_never_receive_ctrl_c(pool: LocalBackend) -> None:
    """A terminal's Ctrl-C goes to the whole process group: the workers (and the forkserver
    that starts them) hold SIGINT blocked, so only the parent sees it, and no worker that is
    still starting dies of it with a traceback."""
    import functools
    import signal

    mask = functools.partial(signal.pthread_sigmask, signal.SIG_BLOCK)  # adds nothing: reads
    [(_, blocked)] = list(pool.run(mask, [[]]))
    assert signal.SIGINT in blocked
    assert signal.SIGINT not in signal.pthread_sigmask(signal.SIG_BLOCK, [])  # the parent's


def test_a_crashing_worker_fails_its_round_and_the_batch_goes_on(
    clean: Path,
    settings: EvalSettings,
    pool: LocalBackend,
    reference: tuple[Evaluation, Tables],
    tmp_path: Path,
) -> None:
    crashy = write_match(tmp_path / "crashy.json", walking_match("match-c", 23))
    evaluation = run_evaluation([clean, crashy], settings, tmp_path / "out", pool, job=crashing_job)
    assert [(Path(f.file).name, f.round_num, f.kind) for f in evaluation.failures] == [
        ("crashy.json", 2, "worker crash")
    ]
    assert "worker process died" in evaluation.failures[0].message
    assert evaluation.computed == CLEAN_ROUNDS + 1
    players = build_tables(evaluation.accumulator).players
    clean_rows = players[players["match"] != "match-c"].reset_index(drop=True)
    pd.testing.assert_frame_equal(clean_rows, reference[1].players)


@pytest.fixture(scope="module")
def messy(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """One good match and every kind of bad input, in one folder."""
    folder = tmp_path_factory.mktemp("messy")
    write_match(folder / "good.json.xz", walking_match("match-good", 5))
    broken = walking_match("match-broken", 7, keep_round3=True)  # round 3: no frames
    broken["gameRounds"][1]["frames"][2]["t"]["players"][0]["x"] = float("nan")
    write_match(folder / "broken.json", broken)
    write_match(folder / "nuke.json.xz", {**walking_match("match-nuke", 3), "mapName": "de_nuke"})
    data = lzma.compress(json.dumps(make_match()).encode())
    (folder / "truncated.json.xz").write_bytes(data[: len(data) // 2])
    (folder / "settings.json").write_text(json.dumps({"volume": 11}))
    (folder / "notes.txt").write_text("not a match")
    return folder


def test_bad_input_is_reported_per_file_and_round_and_the_exit_code_says_so(
    messy: Path, tmp_path: Path
) -> None:
    out = tmp_path / "out"
    # bomb on, nobody shoots: the other mechanics path of the same run
    result = _invoke(
        str(messy), "--combat", "--models", "none", "--workers", "1", "--no-figures",
        "--out", str(out),
    )  # fmt: skip
    assert result.exit_code == 1
    last = result.output.strip().splitlines()[-1]
    assert last.startswith("error: 5 files or rounds failed (3 rounds evaluated)")
    assert "Traceback" not in result.output
    failures = pd.read_csv(out / "failures.csv").fillna({"round": -1})
    found = {
        (name, int(num), kind)
        for name, num, kind in zip(
            failures["file"].map(lambda f: Path(f).name),
            failures["round"],
            failures["kind"],
            strict=True,
        )
    }
    assert found == {
        ("broken.json", 2, "broken round"),  # a NaN position: the reader rejects the round
        ("broken.json", 3, "replay error"),  # no frames: nothing to replay
        ("nuke.json.xz", -1, "other map"),
        ("truncated.json.xz", -1, "unreadable file"),
        ("settings.json", -1, "unreadable file"),
    }
    assert any("a de_nuke match" in message for message in failures["message"])
    summary = json.loads((out / "summary.json").read_text())
    assert summary["counts"]["ignored_files"] == 1  # notes.txt
    assert summary["options"]["bomb"] is True
    report = (out / "report.md").read_text()
    assert "5 files or rounds produced no result" in report
    assert len(pd.read_csv(out / "rounds.csv")) == 3  # good 1, 2 and broken 1


def test_a_full_disk_stops_with_one_line_and_keeps_what_was_cached(
    clean: Path, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    stored: list[str] = []
    real_store = RunCache.store_round

    def store(cache: RunCache, record: Any) -> None:
        if stored:
            raise OutputError(f"cannot write {cache.round_path(record.key)}: No space left")
        real_store(cache, record)
        stored.append(record.key)

    monkeypatch.setattr(RunCache, "store_round", store)
    out = tmp_path / "out"
    result = _invoke(str(clean), "--no-combat", "--no-bomb", "--workers", "1", "--out", str(out))
    assert result.exit_code == 1
    assert result.output.strip().splitlines()[-1].startswith("error: cannot write")
    assert "No space left" in result.output and "Traceback" not in result.output
    assert [p.stem for p in (out / "cache" / "rounds").glob("*.msgpack")] == stored


def test_missing_inputs_and_bad_options_are_one_line(clean: Path, tmp_path: Path) -> None:
    for args, expected in (
        ([str(tmp_path / "nowhere")], "no such file or folder"),
        ([str(tmp_path), "--combat"], "no match files in this folder"),
        ([str(clean), "--map", "cache"], "unknown map 'cache'"),
        ([str(clean), "--combat", "--models", str(tmp_path / "no-models")], "no such model"),
    ):
        result = _invoke(*args, "--out", str(tmp_path / "out"))
        assert result.exit_code == 1, args
        assert result.output.startswith("error: ") and expected in result.output, result.output
        assert len(result.output.strip().splitlines()) == 1
    # a choice the option does not have is a usage error: one line too, exit code 2
    result = _invoke(str(clean), "--mover", "teleport", "--out", str(tmp_path / "out"))
    assert result.exit_code == 2 and len(result.output.strip().splitlines()) == 1
    assert result.output.startswith("error: Invalid value for '--mover'"), result.output
    assert "'kinematic', 'physics'" in result.output and "evaluate --help" in result.output


def test_a_copy_of_the_shipped_graph_gives_the_shipped_results(
    clean: Path, reference: tuple[Evaluation, Tables], tmp_path: Path
) -> None:
    copy = tmp_path / "my.npz"
    copy.write_bytes((asset_dir() / GRAPH_FILE).read_bytes())
    settings = make_settings(
        map_name="dust2",
        combat=False,
        bomb=False,
        models="shipped",
        mover="kinematic",
        seed=0,
        graph=copy,
    )
    assert settings.graph == str(copy.resolve()) and settings.graph_sha
    assert round_key(settings, "f", 1) != round_key(reference[0].settings, "f", 1)
    with LocalBackend(1) as backend:
        evaluation = run_evaluation([clean], settings, tmp_path / "out", backend)
    assert_same_results(evaluation, reference)


def test_a_bad_graph_is_one_line(clean: Path, tmp_path: Path) -> None:
    other_map = asset_dir("de_mirage") / GRAPH_FILE
    not_a_graph = tmp_path / "notes.npz"
    not_a_graph.write_text("not a graph")
    for graph, expected in (
        (other_map, "a graph of de_mirage, not de_dust2"),
        (tmp_path / "missing.npz", "missing.npz"),
        (not_a_graph, "notes.npz"),
    ):
        result = _invoke(str(clean), "--graph", str(graph), "--out", str(tmp_path / "out"))
        assert result.exit_code == 1, result.output
        assert result.output.startswith("error: ") and expected in result.output, result.output
        assert len(result.output.strip().splitlines()) == 1


# ---- the default sample, synthetic data ---------------------------------------------------------


def test_without_input_the_shipped_sample_is_evaluated_and_called_synthetic(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    from decoy_cli.synth import sample as shipped

    monkeypatch.setattr(shipped, "SAMPLE_DIR", tmp_path / "missing")
    result = _invoke("--no-combat", "--no-bomb", "--out", str(tmp_path / "out"))
    assert result.exit_code == 1 and "no shipped sample" in result.output

    sample = tmp_path / "sample"
    sample.mkdir()
    document = walking_match("synthetic-dust2-seed0", 2)
    document["provenance"] = {"generator": "decoy make-sample", "seed": 0}
    write_match(sample / "synthetic-dust2-seed0.json.xz", document)
    monkeypatch.setattr(shipped, "SAMPLE_DIR", sample)
    out = tmp_path / "out"
    result = _invoke(
        "--no-combat", "--no-bomb", "--no-figures", "--workers", "1", "--out", str(out)
    )
    assert result.exit_code == 0, result.output
    assert "data: synthetic" in result.output
    assert "**Data: synthetic.**" in (out / "report.md").read_text()
    assert json.loads((out / "summary.json").read_text())["data"] == "synthetic"


def test_synthetic_is_read_from_the_match_id_or_the_provenance() -> None:
    assert is_synthetic("synthetic-dust2-seed0", None)
    assert is_synthetic("m1", {"note": "Synthetic rounds played by the simulator"})
    assert not is_synthetic("00e7fec9", {"upstream": "ESTA", "recorded": "T players"})


# ---- compact per-round data ---------------------------------------------------------------------


def test_hp_sums_give_the_library_hp_metrics_exactly() -> None:
    rng = np.random.default_rng(7)
    original_parts, replay_parts, frame_parts = [], [], []
    pooled = [0] * 7
    frames = np.zeros((3, 0), np.int64)
    for _ in range(6):  # six rounds of random length
        count = int(rng.integers(20, 80))
        frame_index = np.sort(rng.integers(0, 40, count))
        original = rng.integers(0, 101, count)
        replay = np.clip(original - rng.integers(-20, 30, count), 0, 100)
        stats = hp_stats(original, replay, frame_index, np.arange(40) * 0.5, 1.0, 240)
        pooled = [a + b for a, b in zip(pooled, stats.pooled, strict=True)]
        part = np.array([stats.frame_count, stats.frame_sum_original, stats.frame_sum_replay])
        grown = np.zeros((3, max(frames.shape[1], part.shape[1])), np.int64)
        grown[:, : frames.shape[1]] += frames
        grown[:, : part.shape[1]] += part
        frames = grown
        original_parts.append(original)
        replay_parts.append(replay)
        frame_parts.append(frame_index)
    values, reasons, n = hp_metrics_from_sums(pooled, frames)
    library = hp_metrics(
        np.concatenate(original_parts), np.concatenate(replay_parts), np.concatenate(frame_parts)
    )
    assert n == library.n_player_frames and not reasons
    for name, value in library.values.items():
        assert values[name] == pytest.approx(value, rel=1e-12), name


def test_hp_sums_of_constant_series_say_why_there_is_no_correlation() -> None:
    stats = hp_stats(np.full(5, 100), np.full(5, 100), np.arange(5), np.arange(5.0), 1.0, 240)
    frames = np.array([stats.frame_count, stats.frame_sum_original, stats.frame_sum_replay])
    values, reasons, _ = hp_metrics_from_sums(stats.pooled, frames)
    assert np.isnan(values["hp_corr"]) and reasons["hp_corr"] == "original series is constant"
    assert values["hp_rmse"] == 0.0


def test_a_position_off_the_graph_gets_the_place_below_it() -> None:
    graph = builtin_graph()
    finder = PlaceFinder(graph)
    node = int(graph.region_of("bombsite_a")[0])
    on = graph.positions[node]
    above = on + np.array([0.0, 0.0, 5.0])  # no waypoint on a floor 5 m up
    place, on_floor = finder.find(np.array([on, above]))
    assert list(on_floor) == [True, False]
    assert place[0] == place[1] == graph.node_place[node]
    assert finder.names[place[0]] == graph.place_names[graph.node_place[node]]


def test_grid_sums_are_a_2d_histogram_on_the_fixed_grid() -> None:
    grid = HeatGrid.for_map("de_dust2")
    rng = np.random.default_rng(3)
    points = np.column_stack(
        [
            rng.uniform(grid.extent[0] - 5, grid.extent[1] + 5, 3000),
            rng.uniform(grid.extent[2] - 5, grid.extent[3] + 5, 3000),
            np.zeros(3000),
        ]
    )
    weights = rng.integers(0, 5000, 3000)
    bins = (grid.ny, grid.nx)
    box = ((grid.extent[2], grid.extent[3]), (grid.extent[0], grid.extent[1]))
    counts, _, _ = np.histogram2d(points[:, 1], points[:, 0], bins=bins, range=box)
    sums, _, _ = np.histogram2d(points[:, 1], points[:, 0], bins=bins, range=box, weights=weights)
    cells, got_counts, got_sums = read_grid_sums(grid_sums(grid, points, weights), 3)
    dense = np.zeros((2, grid.size), np.int64)
    dense[0, cells], dense[1, cells] = got_counts, got_sums
    assert np.array_equal(dense[0], counts.reshape(-1).astype(np.int64))
    assert np.array_equal(dense[1], sums.reshape(-1).astype(np.int64))


# ---- Dask ---------------------------------------------------------------------------------------


def test_a_dask_cluster_gives_the_local_numbers(
    clean: Path, reference: tuple[Evaluation, Tables], tmp_path: Path
) -> None:
    distributed = pytest.importorskip("distributed", reason="the dask extra is not installed")
    with distributed.LocalCluster(
        n_workers=2,
        threads_per_worker=1,
        processes=True,
        host="127.0.0.1",
        dashboard_address=None,
    ) as cluster:
        address = cluster.scheduler_address
        result = _invoke(
            str(clean), "--no-combat", "--no-bomb", "--no-figures", "--scheduler", address,
            "--out", str(tmp_path),
        )  # fmt: skip
    assert result.exit_code == 0, result.output
    assert f"Dask scheduler {address}" in result.output
    tables = reference[1]
    assert (tmp_path / "players.csv").read_text() == tables.players.to_csv(index=False)
    for name in ("trajectory", "combat", "places", "hp_over_time"):
        frame = tables.hp_curve if name == "hp_over_time" else getattr(tables, name)
        assert (tmp_path / "tables" / f"{name}.csv").read_text() == frame.to_csv(index=False)


def test_an_unreachable_scheduler_is_one_line() -> None:
    pytest.importorskip("distributed", reason="the dask extra is not installed")
    with pytest.raises(DecoyError, match="cannot connect to the Dask scheduler at tcp://"):
        DaskBackend("tcp://127.0.0.1:9", timeout_s=0.5)


# ---- real data ----------------------------------------------------------------------------------


def test_real_t_side_rounds(settings: EvalSettings, pool: LocalBackend, tmp_path: Path) -> None:
    if not TSIDE.is_dir():
        pytest.skip(f"real ESTA data not present at {TSIDE}")
    file = sorted(TSIDE.glob("*.json.xz"))[0]
    evaluation = run_evaluation([file], settings, tmp_path, pool, sample=3)
    tables = build_tables(evaluation.accumulator)
    assert not evaluation.failures and evaluation.computed == 3
    assert set(tables.players["side"]) == {"T"} and tables.rounds_both_teams == 0
    assert tables.outcome is None  # the export did not record the winners
    t = tables.trajectory[tables.trajectory["group"] == "T"].set_index("metric")
    assert 0 < t.loc["mean_dist", "mean"] < 5 and t.loc["paper_dtw", "paper_mean"] == 0.873


def test_the_main_job_on_the_shipped_sample_with_combat(tmp_path: Path) -> None:
    """`decoy evaluate` as the README runs it: the shipped synthetic sample, combat and bomb
    on with the default damage model, the shipped DIP and the game's rules (here on 3 sampled
    rounds, one worker)."""
    out = tmp_path / "out"
    result = _invoke("--sample", "3", "--workers", "1", "--out", str(out))
    assert result.exit_code == 0, result.output
    assert "data: synthetic" in result.output
    combat = pd.read_csv(out / "tables" / "combat.csv").set_index("metric")
    assert combat.loc["outcome_agreement", "n"] == 3
    rounds = pd.read_csv(out / "rounds.csv")
    assert len(rounds) == 3 and rounds["winner_replay"].isin(["T", "CT"]).all()
    # the share of the rounds (all with a recorded winner) that were played on after the data
    played_on = int((rounds["played_out_s"] > 0).sum())
    assert combat.loc["decided_after_data", "value"] == pytest.approx(played_on / 3)
    report = (out / "report.md").read_text()
    assert "damage model: rules" in report
    # FastDTW only on request outside the paper's Table 2 setting
    assert FASTDTW_METRIC not in pd.read_csv(out / "players.csv").columns
    assert "--no-fastdtw" in report
    for figure in sorted((out / "figures").glob("*.png")):
        assert f"figures/{figure.name}" in report


def test_a_second_run_into_a_held_folder_is_refused(clean: Path, tmp_path: Path) -> None:
    """One writer per output folder: a live run's lock (the kernel's, held by a process)
    refuses a second run with one error line; a lock file no live process holds, whatever
    process id it names, does not stop a run, and a killed run's staging folder and temporary
    cache files are cleared."""
    import fcntl
    import subprocess

    from decoy_cli.evaluate.outputs import LOCK_FILE

    out = tmp_path / "out"
    out.mkdir()
    holder = subprocess.Popen(
        [
            sys.executable,
            "-c",
            "import fcntl, os, sys, time\n"
            "fd = os.open(sys.argv[1], os.O_RDWR | os.O_CREAT)\n"
            "fcntl.flock(fd, fcntl.LOCK_EX)\n"
            "os.write(fd, b'%d\\n' % os.getpid())\n"
            "print('held', flush=True)\n"
            "time.sleep(60)",
            str(out / LOCK_FILE),
        ],
        stdout=subprocess.PIPE,
        text=True,
    )
    try:
        assert holder.stdout is not None and holder.stdout.readline() == "held\n"
        refused = _invoke(
            str(clean), "--no-combat", "--no-bomb", "--workers", "1", "--out", str(out)
        )
        assert refused.exit_code == 1
        assert refused.stderr == (
            f"error: {out}: another decoy evaluate (process {holder.pid}) is writing to this "
            "folder; wait for it or choose another --out\n"
        )
        assert sorted(p.name for p in out.iterdir()) == [LOCK_FILE]
    finally:
        holder.kill()
        holder.wait()
    # the holder is gone (as after a SIGKILL): its lock file names it, or a live process
    (out / LOCK_FILE).write_text(f"{os.getpid()}\n")
    (out / ".staging-999999" / "tables").mkdir(parents=True)  # left by a killed run
    (out / "cache" / "rounds").mkdir(parents=True)
    (out / "cache" / "rounds" / ".abc.msgpack.x1y2.tmp").write_bytes(b"half")
    done = _invoke(str(clean), "--no-combat", "--no-bomb", "--workers", "1", "--out", str(out))
    assert done.exit_code == 0, done.output
    names = sorted(p.name for p in out.iterdir())
    assert not [n for n in names if n.startswith(".staging")]
    assert not list((out / "cache" / "rounds").glob(".*"))
    assert {"players.csv", "report.md", "summary.json", "tables", "figures"} <= set(names)
    with open(out / LOCK_FILE) as lock:  # released: another process can take it
        fcntl.flock(lock, fcntl.LOCK_EX | fcntl.LOCK_NB)


def test_ctrl_c_while_the_outputs_are_written_keeps_the_last_ones(
    clean: Path, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """A Ctrl-C after the rounds (while the figures are drawn into the staging folder) says
    how to resume, exits 130 and leaves the previous outputs as they were, no staging."""
    from decoy_cli.evaluate import outputs

    out = tmp_path / "out"
    args = (str(clean), "--no-combat", "--no-bomb", "--workers", "1", "--out", str(out))
    assert _invoke(*args, "--no-figures").exit_code == 0  # the previous run's tables
    before = {p: p.read_bytes() for p in out.rglob("*.csv")}

    def pressed(*_: object, **__: object) -> None:
        raise KeyboardInterrupt

    monkeypatch.setattr(outputs, "draw_figures", pressed)
    result = _invoke(*args)
    assert result.exit_code == 130, result.output
    assert "run the same command again to resume" in result.stdout
    assert "Traceback" not in result.output
    assert {p: p.read_bytes() for p in out.rglob("*.csv")} == before
    assert not list(out.glob(".staging*"))


def test_a_ctrl_c_while_outputs_are_written_waits_for_them() -> None:
    """`ctrl_c_deferred`: a SIGINT inside the block lets the block finish, then is raised, and
    the handler from before the block is back (whatever it was: a library loaded by an earlier
    test in the same process may have left SIGINT ignored)."""
    import signal

    from decoy_cli.evaluate.outputs import ctrl_c_deferred

    before = signal.getsignal(signal.SIGINT)
    finished = []
    with pytest.raises(KeyboardInterrupt), ctrl_c_deferred():
        assert signal.getsignal(signal.SIGINT) is not before
        os.kill(os.getpid(), signal.SIGINT)
        finished.append(True)
    assert finished == [True]
    assert signal.getsignal(signal.SIGINT) is before
