"""The shapes of `decoy bench`'s results, as the sections return them and the report writes
them: one `TypedDict` per section (`SectionResult` is any of them, or a skipped or failed
section), the machine, the report and the side-by-side comparison.

Results read back from another code tree's process (`baseline.run_in`) are JSON of whatever
version wrote them: those stay `JsonObject`s, read with care.
"""

from __future__ import annotations

from typing import TypedDict, TypeGuard, final

from decoy_cli.files import JsonObject


class Measured(TypedDict, total=False):
    """What the runner adds to every section's result (`runner.run_section`)."""

    section_wall_s: float
    peak_rss_mb: float
    ru_maxrss_mb: float


@final
class NotMeasured(TypedDict, total=False):
    """A section that did not run (`skipped`: why) or failed (`error`: one line)."""

    skipped: str
    error: str


class DataRecord(TypedDict):
    """The match files a section measured on (`data.BenchData.describe`)."""

    kind: str
    folder: str
    files: int


class SpeedRowRecord(TypedDict):
    """One row of Table 1 (`simspeed.SpeedRow`)."""

    agents: int
    mover: str
    rounds: int
    ticks: int
    decisions: int
    kills: int
    wall_s: float
    cpu_s: float
    game_s: float
    ticks_per_s: float
    time_scale: float
    paper_ticks_per_s: float | None


class PaperFigures(TypedDict):
    """The paper's Table 1, by agent count."""

    source: str
    ticks_per_s: dict[int, float | None]


@final
class Table1Result(Measured):
    """The `table1` section: the paper's Table 1 on this machine."""

    map: str
    mover: str
    combat: bool
    bomb: bool
    decisions_per_row: int
    damage_model: str
    paper: PaperFigures
    rows: list[SpeedRowRecord]


class PortableConfig(TypedDict, total=False):
    """What a portable section (`portable`) reads of the run's settings (the sizes are the
    current code's `BenchConfig`, so that both sides of a side-by-side run measure the same)."""

    quick: bool
    models: str
    combat: bool
    bomb: bool
    seed: int
    map: str
    decisions: int
    combat_agents: list[int]
    combat_repeats: int
    metric_pairs: int
    kernel_repeats: int


@final
class KinematicResult(Measured):
    """The `kinematic` section (`portable.kinematic_section`)."""

    agents: int
    decisions: int
    ticks: int
    wall_s: float
    ticks_per_s: float
    time_scale: float
    damage_model: str


class ArrayFigures(TypedDict, total=False):
    """The `env` section's rounds through the array environment, where the code has one."""

    array_decisions: int
    array_wall_s: float
    array_decisions_per_s: float


@final
class EnvResult(ArrayFigures, Measured):
    """The `env` section (`portable.env_section`)."""

    rounds: int
    mover: str
    decisions: int
    steps: int
    game_s: float
    outcomes: list[str]
    wall_s: float
    cpu_s: float
    decisions_per_s: float
    env_memory_mb: float
    damage_model: str


class StepTimes(TypedDict):
    """Wall times of one part of the combat step, in milliseconds (`combat.summarize_ms`)."""

    median_ms: float
    mean_ms: float
    min_ms: float
    max_ms: float


class CombatRow(TypedDict):
    """One layout of the `combat_step` section (`combat.step_costs`)."""

    agents: int
    layout: str
    steps: int
    parts: dict[str, StepTimes]
    visible_pairs_median: float
    visible_pairs_max: int


@final
class CombatResult(Measured):
    """The `combat_step` section."""

    map: str
    damage_model: str
    rows: list[CombatRow]


class ReplaySettings(TypedDict):
    """How the `replay` section replayed."""

    combat: bool
    bomb: bool
    mover: str
    seed: int


class _ReplayFigures(TypedDict, total=False):
    """The `replay` section's figures, when a round was replayed."""

    frames: int
    wall_s: float
    cpu_s: float
    game_s: float
    rounds_per_s: float
    rounds_per_cpu_s: float | None
    s_per_round_median: float
    time_scale: float
    data: DataRecord
    damage_model: str | None


@final
class ReplayResult(_ReplayFigures, Measured):
    """The `replay` section (`data.replay_throughput`)."""

    rounds: int
    failed: int
    failures: list[str]
    options: ReplaySettings


class KernelRow(StepTimes):
    """One distance kernel on one pair of curves (`portable.kernel_times`), its wall times as
    the combat step's parts'."""

    kernel: str
    size: str
    calls: int


class _MetricsFigures(TypedDict, total=False):
    """The distance kernels alone, beside the throughput (`portable.metrics_section`)."""

    kernels: list[KernelRow]


@final
class MetricsResult(_MetricsFigures, Measured):
    """The `metrics` section (`metrics.metric_throughput`, and the kernels)."""

    pairs: int
    evaluated: int
    mean_frames: float
    wall_s: float
    cpu_s: float
    pairs_per_s: float
    ms_per_pair: float


class _ReaderFigures(TypedDict, total=False):
    """The `reader` section's figures, when a file was read."""

    rounds: int
    compressed_mb: float
    decompressed_mb: float
    seconds: float
    s_per_file_median: float
    s_per_file_min: float
    s_per_file_max: float
    mb_per_s_decompressed: float
    mb_per_s_compressed: float
    rounds_per_s: float
    data: DataRecord


@final
class ReaderResult(_ReaderFigures, Measured):
    """The `reader` section (`data.reader_throughput`)."""

    files: int
    failed: int
    failures: list[str]
    repeats: int


class AwpyReadRecord(TypedDict):
    """One awpy reader on the section's match (`awpy.ReadFigures`)."""

    rows: int
    rounds: int
    seconds: float
    rows_per_s: float
    peak_rss_mb: float


@final
class AwpyResult(Measured):
    """The `awpy` section (`awpy.awpy_reader_throughput`): each reader by name."""

    rounds: int
    readers: dict[str, AwpyReadRecord]


Measurement = (
    Table1Result
    | KinematicResult
    | EnvResult
    | CombatResult
    | ReplayResult
    | MetricsResult
    | ReaderResult
    | AwpyResult
)
"""What a section that ran gave."""

SectionResult = Measurement | NotMeasured
"""What one section gave."""


def not_measured(result: SectionResult) -> TypeGuard[NotMeasured]:
    """Whether the section was skipped or failed."""
    return "skipped" in result or "error" in result


class MachineInfo(TypedDict):
    """The machine a benchmark ran on (`machine.machine_info`)."""

    cores: int | None
    usable_cores: int
    cpu: str
    memory_gb: float | None
    load_average: list[float] | None
    os: str
    python: str
    packages: dict[str, str | None]


class BenchReport(TypedDict):
    """The JSON report of `decoy bench` (`runner.report`)."""

    format: int
    decoy: str
    created: str
    quick: bool
    config: dict[str, object]
    machine: MachineInfo
    load_average_end: list[float] | None
    damage_model: dict[str, object]
    data: DataRecord | None
    sections: dict[str, SectionResult]
    peak_rss_mb_main: float
    ru_maxrss_mb_main: float


class BenchSwitches(TypedDict, total=False):
    """The options a side-by-side run passes to either code tree (`BenchConfig.create`'s
    keywords; `map_name` only off the built-in map, which earlier versions do not know)."""

    quick: bool
    models: str
    mover: str
    combat: bool
    bomb: bool
    seed: int
    map_name: str


class BenchSizes(TypedDict, total=False):
    """How much Table 1 measures, set on either code tree's `BenchConfig` after `create`
    (fields every version of it has)."""

    agent_counts: list[int]
    decisions: int


class RunArgs(TypedDict):
    """What a side-by-side run gives either code tree (`baseline.run_args`): the keywords of
    its `BenchConfig.create`, the sizes set after it, and the portable sections' settings."""

    switches: BenchSwitches
    sizes: BenchSizes
    portable: PortableConfig


class RatioRecord(TypedDict):
    """One headline figure on both sides and the ratios of the pairs (`baseline.Ratio`)."""

    section: str
    figure: str
    current: list[float]
    baseline: list[float]
    ratios: list[float]
    ratio_median: float | None
    ratio_min: float | None
    ratio_max: float | None


class SideBySide(TypedDict):
    """Sections run on the current code and a baseline, alternating (`baseline.side_by_side`):
    every run's result as JSON, the ratios and the errors."""

    current: str
    baseline: str
    repeats: int
    runs: dict[str, dict[str, list[JsonObject]]]
    ratios: list[RatioRecord]
    errors: list[str]
