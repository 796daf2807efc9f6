"""`decoy bench` as data: the sections, their sizes, one fresh process each, and the report.

Every section runs in its own spawned process, so that its peak memory is its own and one
section's caches do not speed up the next. The peak is VmHWM (see `machine.peak_rss_mb`): a
spawned process's ru_maxrss starts at its parent's RSS on Linux; it is reported beside it.

The damage model is checked once in the calling process (`check_damage_model`); a model that
cannot be loaded is reported and the sections fall back to line of sight without inference
(`NeverHits`), labelled as such.
"""

from __future__ import annotations

import datetime
import multiprocessing
import os
import time
from collections.abc import Sequence
from concurrent.futures import ProcessPoolExecutor
from concurrent.futures.process import BrokenProcessPool
from dataclasses import asdict, dataclass, replace

from decoy_cli import __version__
from decoy_cli.bench.awpy import BENCH_ROUNDS, awpy_reader_throughput
from decoy_cli.bench.data import BenchData, reader_throughput, replay_throughput
from decoy_cli.bench.machine import load_average, peak_rss_mb, ru_maxrss_mb
from decoy_cli.bench.portable import COMBAT_AGENTS, PORTABLE_SECTIONS
from decoy_cli.bench.records import (
    BenchReport,
    MachineInfo,
    Measurement,
    PortableConfig,
    SectionResult,
)
from decoy_cli.bench.simspeed import (
    AGENT_COUNTS,
    PAPER_DECISIONS,
    PAPER_TICKS_PER_S,
    speed_table,
)
from decoy_cli.csgo import BUILTIN_MAP
from decoy_cli.damage.choice import ModelChoice, ModelName
from decoy_cli.errors import DecoyError
from decoy_cli.sim.setup import MoverName, RunSpec
from decoy_cli.waypoints.build import builtin_graph, canonical_map

REPORT_FORMAT = 1

SECTIONS = ("table1", "kinematic", "env", "combat_step", "replay", "metrics", "reader", "awpy")
"""Section keys of the report, in the order they run."""

DATA_SECTIONS = ("replay", "reader")
"""Sections that need match files; skipped, with the reason, when there are none."""

MODEL_SECTIONS = ("table1", "replay")
"""Sections given the damage model checked here (the portable ones load their own; the
others do not load it, nor torch)."""

PAPER = "DECOY paper (Wang, Ustun, McGroarty, WSC 2025), Table 1"


@dataclass(frozen=True, kw_only=True)
class BenchConfig(RunSpec):
    """What to run and how much of it: the full benchmark, or a quick smoke run.

    `combat` and `bomb` (`RunSpec`) switch the mechanics of Table 1 and of the replay section
    (the paper's Table 1 has every mechanic on); Table 1 runs the paper's physics mover.
    `agent_counts` are Table 1's rows, `decisions` the agent decisions of each row and of the
    kinematic row, `combat_agents` the sizes of the combat step (half T, half CT)."""

    quick: bool
    models: ModelChoice
    mover: MoverName = "physics"
    map_name: str = BUILTIN_MAP
    agent_counts: tuple[int, ...] = AGENT_COUNTS
    decisions: int = PAPER_DECISIONS
    combat_agents: tuple[int, ...] = (COMBAT_AGENTS,)
    combat_repeats: int = 300
    replay_rounds: int | None = None
    metric_pairs: int = 2000
    kernel_repeats: int = 500
    reader_files: int | None = None
    awpy_rounds: int = BENCH_ROUNDS

    @classmethod
    def create(
        cls,
        *,
        quick: bool,
        models: ModelChoice,
        mover: MoverName = "physics",
        combat: bool = True,
        bomb: bool = True,
        seed: int = 0,
        map_name: str = BUILTIN_MAP,
        agent_counts: Sequence[int] | None = None,
        decisions: int | None = None,
        combat_agents: Sequence[int] | None = None,
    ) -> BenchConfig:
        """The full sizes (the paper's 10,000 decisions at 2-100 agents, every data file and
        round), or the quick ones (1,000 decisions at 2 and 10 agents, a few rounds and files);
        Table 1's agent counts and decisions and the combat step's agent counts where given
        (checked against the map's spawns and waypoints: `check_sizes`)."""
        config = cls(
            quick=quick,
            models=models,
            mover=mover,
            combat=combat,
            bomb=bomb,
            seed=seed,
            map_name=canonical_map(map_name),
        )
        if quick:
            config = replace(
                config,
                agent_counts=(2, 10),
                decisions=1_000,
                combat_repeats=20,
                replay_rounds=3,
                metric_pairs=100,
                kernel_repeats=50,
                reader_files=2,
                awpy_rounds=4,
            )
        check_sizes(config.map_name, agent_counts, decisions, combat_agents)
        return replace(
            config,
            agent_counts=config.agent_counts if agent_counts is None else _once(agent_counts),
            decisions=config.decisions if decisions is None else decisions,
            combat_agents=config.combat_agents if combat_agents is None else _once(combat_agents),
        )


def _once(counts: Sequence[int]) -> tuple[int, ...]:
    """The counts in the order given, each once."""
    return tuple(dict.fromkeys(counts))


def check_sizes(
    map_name: str,
    agent_counts: Sequence[int] | None,
    decisions: int | None,
    combat_agents: Sequence[int] | None,
) -> None:
    """A DecoyError that says which size given is wrong, if one is: Table 1 places its agents
    on spawn waypoints (half T, half CT, distinct waypoints) and the combat step on any
    waypoints, so the map's graph bounds both."""
    if decisions is not None and decisions < 1:
        raise DecoyError(f"--decisions {decisions}: give at least 1 agent decision")
    if agent_counts is None and combat_agents is None:
        return
    graph = builtin_graph(map_name)
    if agent_counts is not None:
        t_room, ct_room = (len(graph.region_of(side)) for side in ("t_spawn", "ct_spawn"))
        room = min(2 * t_room + 1, 2 * ct_room)  # n // 2 T, the rest CT
        wrong = [n for n in agent_counts if not 2 <= n <= room]
        if wrong or not agent_counts:
            raise DecoyError(
                f"--agents {wrong[0] if wrong else '(none)'}: Table 1 plays 2 to {room} agents "
                f"on {map_name} (its spawns' waypoints, half T and half CT)"
            )
    if combat_agents is not None:
        room = graph.num_nodes - graph.num_nodes % 2
        wrong = [n for n in combat_agents if n % 2 or not 2 <= n <= room]
        if wrong or not combat_agents:
            raise DecoyError(
                f"--combat-agents {wrong[0] if wrong else '(none)'}: give an even count from 2 "
                f"to {room} (half T, half CT, on distinct waypoints of {map_name})"
            )


@dataclass(frozen=True)
class ModelStatus:
    """The damage model the sections use, as the report states it."""

    choice: ModelChoice
    loaded: bool
    label: str
    error: str | None = None


def check_damage_model(choice: ModelChoice) -> ModelStatus:
    """Try to load the chosen damage model; on failure say why (the sections fall back)."""
    from decoy_cli.damage import load_damage_model

    if choice == ModelName.NONE:
        return ModelStatus(choice, False, "none (--models none): line of sight only, no inference")
    try:
        model = load_damage_model(choice)
    except DecoyError as error:
        return ModelStatus(
            choice,
            False,
            "none (loading failed): line of sight only, no inference",
            error=str(error),
        )
    if model is None:
        return ModelStatus(choice, False, "none: line of sight only, no inference")
    from decoy_cli.damage.rules_damage import RulesDamage

    outcome = "the game's damage rules" if isinstance(model, RulesDamage) else "DOG"
    return ModelStatus(choice, True, f"learned DIP + {outcome} ({choice})")


def run_section(
    name: str, config: BenchConfig, status: ModelStatus, data: BenchData | None
) -> Measurement:
    """Run one section in this process; its result with wall time and peak memory."""
    model = None
    if status.loaded and name in MODEL_SECTIONS:
        from decoy_cli.damage import load_damage_model

        model = load_damage_model(status.choice)
    started = time.perf_counter()
    result: Measurement
    if name == "table1":
        rows = speed_table(
            config.agent_counts,
            config.decisions,
            model,
            mover=config.mover,
            combat=config.combat,
            bomb=config.bomb,
            seed=config.seed,
            map_name=config.map_name,
        )
        result = {
            "map": config.map_name,
            "mover": config.mover,
            "combat": config.combat,
            "bomb": config.bomb,
            "decisions_per_row": config.decisions,
            "damage_model": status.label,
            "paper": {"source": PAPER, "ticks_per_s": PAPER_TICKS_PER_S},
            "rows": [row.to_dict() for row in rows],
        }
    elif name in PORTABLE_SECTIONS:
        result = PORTABLE_SECTIONS[name](portable_config(config))
    elif name == "replay":
        data = _needed(data, name)
        replayed = replay_throughput(
            data.files,
            config.replay_rounds,
            model,
            combat=config.combat,
            bomb=config.bomb,
            seed=config.seed,
        )
        replayed["data"] = data.describe()
        replayed["damage_model"] = status.label if model else None
        result = replayed
    elif name == "reader":
        data = _needed(data, name)
        files = data.files[: config.reader_files] if config.reader_files else data.files
        read = reader_throughput(files)
        read["data"] = data.describe()
        result = read
    elif name == "awpy":
        result = {
            "rounds": config.awpy_rounds,
            "readers": awpy_reader_throughput(config.awpy_rounds),
        }
    else:
        raise ValueError(f"no bench section {name!r}; the sections are {', '.join(SECTIONS)}")
    result["section_wall_s"] = time.perf_counter() - started
    result["peak_rss_mb"] = peak_rss_mb()
    result["ru_maxrss_mb"] = ru_maxrss_mb()
    return result


def portable_config(config: BenchConfig) -> PortableConfig:
    """What a portable section (`decoy_cli.bench.portable`) reads of the config."""
    settings: PortableConfig = {
        "quick": config.quick,
        "models": str(config.models),
        "combat": config.combat,
        "bomb": config.bomb,
        "seed": config.seed,
        "decisions": config.decisions,
        "combat_agents": list(config.combat_agents),
        "combat_repeats": config.combat_repeats,
        "metric_pairs": config.metric_pairs,
        "kernel_repeats": config.kernel_repeats,
    }
    if config.map_name != BUILTIN_MAP:  # only then: earlier versions' sections know no map
        settings["map"] = config.map_name
    return settings


def _needed(data: BenchData | None, name: str) -> BenchData:
    if data is None:
        raise ValueError(f"the {name} section needs match files")
    return data


def _quiet_process() -> None:
    """Start a section process with stdout on /dev/null (its results go back as data) and
    pybullet imported without its banner (see `load_pybullet`)."""
    from decoy_cli.world.physics import load_pybullet

    devnull = os.open(os.devnull, os.O_WRONLY)
    os.dup2(devnull, 1)
    os.close(devnull)
    load_pybullet()


def run_isolated(
    name: str, config: BenchConfig, status: ModelStatus, data: BenchData | None
) -> SectionResult:
    """`run_section` in a fresh spawned process; a failure becomes {"error": one line}."""
    if name in DATA_SECTIONS and data is None:
        return {
            "skipped": "no match files: neither the real data "
            "(../shared/data/esta_dust2_tside) nor the sample (examples/sample/) exists; "
            "pass --data FOLDER"
        }
    context = multiprocessing.get_context("spawn")
    try:
        with ProcessPoolExecutor(
            max_workers=1, mp_context=context, initializer=_quiet_process
        ) as pool:
            return pool.submit(run_section, name, config, status, data).result()
    except DecoyError as error:
        return {"error": str(error)}
    except BrokenProcessPool:
        return {"error": f"the {name} process died (killed, or crashed in native code)"}


def report(
    config: BenchConfig,
    status: ModelStatus,
    data: BenchData | None,
    sections: dict[str, SectionResult],
    machine: MachineInfo,
) -> BenchReport:
    """The whole benchmark as one JSON-ready document; `machine` as `machine_info()` said at
    the start (the load average at the end is added)."""
    return {
        "format": REPORT_FORMAT,
        "decoy": __version__,
        "created": datetime.datetime.now(datetime.UTC).isoformat(timespec="seconds"),
        "quick": config.quick,
        "config": {k: v for k, v in asdict(config).items() if k != "models"},
        "machine": machine,
        "load_average_end": load_average(),
        "damage_model": {**asdict(status), "choice": str(status.choice)},
        "data": data.describe() if data is not None else None,
        "sections": sections,
        "peak_rss_mb_main": peak_rss_mb(),
        "ru_maxrss_mb_main": ru_maxrss_mb(),
    }


def failed_sections(sections: dict[str, SectionResult]) -> list[str]:
    """Names of the sections that ended in an error."""
    return [name for name, result in sections.items() if "error" in result]
