"""The tables `decoy bench` prints (not a command): each section's result, the machine and the
side-by-side speed-ups."""

from __future__ import annotations

from typing import cast

from rich.console import Group
from rich.table import Table
from rich.text import Text

from decoy_cli.bench.records import (
    AwpyResult,
    CombatResult,
    EnvResult,
    KinematicResult,
    MachineInfo,
    MetricsResult,
    ReaderResult,
    ReplayResult,
    SectionResult,
    SideBySide,
    Table1Result,
    not_measured,
)

TITLES = {
    "table1": "Table 1: simulator speed",
    "kinematic": "kinematic core, Table 1 at 10 agents",
    "env": "environment, 5v5",
    "combat_step": "one combat step",
    "replay": "replay throughput",
    "metrics": "metric throughput",
    "reader": "reader throughput",
    "awpy": "awpy readers, full-rate ticks",
}


def ratio_table(result: SideBySide) -> Table:
    """The speed-ups of a side-by-side run, figure by figure."""
    table = _table(
        f"speed-up of the current code over {result['baseline']}, measured side by side",
        ["section", "figure", "current (min-max)", "baseline (min-max)", "ratio", "min", "max"],
        caption=f"{result['repeats']} alternating runs per side, each in a fresh process; "
        "ratio = current / baseline of each alternating pair",
    )
    for row in result["ratios"]:
        table.add_row(
            TITLES[row["section"]],
            row["figure"],
            f"{min(row['current']):,.4g}-{max(row['current']):,.4g}",
            f"{min(row['baseline']):,.4g}-{max(row['baseline']):,.4g}",
            f"{row['ratio_median']:.2f}x" if row["ratio_median"] else "-",
            f"{row['ratio_min']:.2f}x" if row["ratio_min"] else "-",
            f"{row['ratio_max']:.2f}x" if row["ratio_max"] else "-",
        )
    return table


def machine_line(machine: MachineInfo) -> str:
    """The machine in one line: cores, CPU, memory, versions and load."""
    packages = machine["packages"]
    versions = ", ".join(
        f"{name} {packages[name]}" for name in ("numpy", "torch", "pybullet") if packages[name]
    )
    memory = f", {machine['memory_gb']:.0f} GB" if machine["memory_gb"] else ""
    return (
        f"machine: {machine['cores']} cores ({machine['usable_cores']} usable), "
        f"{machine['cpu']}{memory}; python {machine['python']}, {versions}; "
        f"load average {load_text(machine['load_average'])}"
    )


def load_text(load: list[float] | None) -> str:
    """The 1-minute load average, or "unknown"."""
    return f"{load[0]:.2f} (1 min)" if load else "unknown"


def section_table(name: str, result: SectionResult) -> Table | Text | Group:
    """The section's table, or one line when it was skipped or failed (the section's name
    says which result it is)."""
    title = TITLES[name]
    if not_measured(result):
        if "skipped" in result:
            return Text(f"{title}: skipped ({result['skipped']})", style="yellow")
        return Text(f"{title}: failed: {result.get('error')}", style="red")
    if name == "table1":
        return _table1(cast(Table1Result, result))
    if name == "kinematic":
        return _kinematic_table(cast(KinematicResult, result))
    if name == "env":
        return _env_table(cast(EnvResult, result))
    if name == "combat_step":
        return _combat_table(cast(CombatResult, result))
    if name == "replay":
        return _replay_table(cast(ReplayResult, result))
    if name == "metrics":
        return _metrics_table(cast(MetricsResult, result))
    if name == "reader":
        return _reader_table(cast(ReaderResult, result))
    if name == "awpy":
        return _awpy_table(cast(AwpyResult, result))
    raise KeyError(name)


def _table(title: str, columns: list[str], caption: str | None = None) -> Table:
    table = Table(title=title, caption=caption)
    for k, column in enumerate(columns):
        table.add_column(column, justify="left" if k == 0 else "right")
    return table


def _table1(result: Table1Result) -> Table:
    table = _table(
        f"Table 1: simulator speed, {result['decisions_per_row']:,} agent decisions per row",
        [
            "agents",
            "physics ticks",
            "decisions",
            "rounds",
            "kills",
            "wall s",
            "CPU s",
            "game s",
            "ticks/s",
            "time scale",
            "paper's table, ticks/s",
        ],
        caption=(
            f"{result['mover']} mover, bomb rules {'on' if result['bomb'] else 'off'}, "
            + (
                f"combat step every 0.5 s with damage model: {result['damage_model']}"
                if result["combat"]
                else "no combat step"
            )
            + f"; peak memory {result['peak_rss_mb']:.0f} MB. The paper's figures come from "
            "its machine: they do not compare with this one's (measure a speed-up side by side "
            "with --baseline)"
        ),
    )
    for row in result["rows"]:
        paper = row["paper_ticks_per_s"]
        table.add_row(
            str(row["agents"]),
            f"{row['ticks']:,}",
            f"{row['decisions']:,}",
            str(row["rounds"]),
            str(row["kills"]),
            f"{row['wall_s']:.2f}",
            f"{row['cpu_s']:.2f}",
            f"{row['game_s']:.1f}",
            f"{row['ticks_per_s']:,.0f}",
            f"{row['time_scale']:.1f}x",
            f"{paper:,g}" if paper else "–",
        )
    return table


def _kinematic_table(result: KinematicResult) -> Table:
    table = _table(
        f"kinematic core: Table 1's protocol at {result['agents']} agents, event by event",
        ["decisions", "ticks", "wall s", "ticks/s", "time scale"],
        caption=f"damage model: {result['damage_model']}; peak memory "
        f"{result['peak_rss_mb']:.0f} MB",
    )
    table.add_row(
        f"{result['decisions']:,}",
        f"{result['ticks']:,}",
        f"{result['wall_s']:.2f}",
        f"{result['ticks_per_s']:,.0f}",
        f"{result['time_scale']:.1f}x",
    )
    return table


def _env_table(result: EnvResult) -> Table:
    table = _table(
        "environment: random masked actions, 5v5, combat and bomb on",
        [
            "interface",
            "rounds",
            "agent decisions",
            "env steps",
            "game s",
            "wall s",
            "decisions/s",
            "env MB",
        ],
        caption=f"{result['mover']} mover, damage model: {result['damage_model']}; env MB: "
        f"peak resident memory the environment added; peak memory {result['peak_rss_mb']:.0f} MB",
    )
    table.add_row(
        "PettingZoo",
        str(result["rounds"]),
        f"{result['decisions']:,}",
        f"{result['steps']:,}",
        f"{result['game_s']:.0f}",
        f"{result['wall_s']:.2f}",
        f"{result['decisions_per_s']:,.0f}",
        f"{result['env_memory_mb']:.0f}",
    )
    if "array_decisions_per_s" in result:
        table.add_row(
            "arrays (DecoyArrayEnv)",
            str(result["rounds"]),
            f"{result['array_decisions']:,}",
            "",
            "",
            f"{result['array_wall_s']:.2f}",
            f"{result['array_decisions_per_s']:,.0f}",
            "",
        )
    return table


def _combat_table(result: CombatResult) -> Table:
    table = _table(
        "one combat step, median ms",
        [
            "agents",
            "layout",
            "steps",
            "line of sight",
            "batch",
            "model",
            "damage",
            "step",
            "visible pairs",
        ],
        caption=f"half T, half CT; damage model: {result['damage_model']}; peak memory "
        f"{result['peak_rss_mb']:.0f} MB",
    )
    for row in result["rows"]:
        parts = row["parts"]
        table.add_row(
            str(row["agents"]),
            row["layout"],
            str(row["steps"]),
            *(
                f"{parts[part]['median_ms']:.3f}"
                for part in ("visible_pairs", "make_batch", "model", "apply_damage", "step")
            ),
            f"{row['visible_pairs_median']:g} (max {row['visible_pairs_max']})",
        )
    return table


def _replay_table(result: ReplayResult) -> Table:
    options = result["options"]
    combat = f"on ({result.get('damage_model')})" if options["combat"] else "off"
    table = _table(
        f"replay throughput ({result['data']['kind']} data), one process",
        ["rounds", "failed", "frames", "wall s", "rounds/s", "rounds per CPU s", "s per round"],
        caption=f"snap + plan + replay + metrics; {options['mover']} mover, bomb "
        f"{'on' if options['bomb'] else 'off'}, combat {combat}; "
        f"peak memory {result['peak_rss_mb']:.0f} MB",
    )
    if not result["rounds"]:
        table.add_row("0", str(result["failed"]), "–", "–", "–", "–", "–")
        return table
    per_cpu = result["rounds_per_cpu_s"]
    table.add_row(
        str(result["rounds"]),
        str(result["failed"]),
        f"{result['frames']:,}",
        f"{result['wall_s']:.2f}",
        f"{result['rounds_per_s']:.2f}",
        f"{per_cpu:.2f}" if per_cpu else "–",
        f"{result['s_per_round_median']:.3f}",
    )
    return table


def _metrics_table(result: MetricsResult) -> Table | Group:
    table = _table(
        "metric throughput (ten metrics, both protocols, one thread)",
        ["player-round pairs", "mean frames", "wall s", "pairs/s", "ms per pair"],
        caption=f"synthetic trajectories; peak memory {result['peak_rss_mb']:.0f} MB",
    )
    table.add_row(
        f"{result['pairs']:,}",
        f"{result['mean_frames']:.0f}",
        f"{result['wall_s']:.2f}",
        f"{result['pairs_per_s']:,.0f}",
        f"{result['ms_per_pair']:.3f}",
    )
    if "kernels" not in result:
        return table
    kernels = _table(
        "distance kernels alone, ms per call",
        ["kernel", "curves", "calls", "median", "min", "max"],
        caption="exact DTW and discrete Fréchet (3-D, or x-y alone) on random walks",
    )
    for row in result["kernels"]:
        kernels.add_row(
            row["kernel"],
            row["size"],
            str(row["calls"]),
            f"{row['median_ms']:.3f}",
            f"{row['min_ms']:.3f}",
            f"{row['max_ms']:.3f}",
        )
    return Group(table, kernels)


def _reader_table(result: ReaderResult) -> Table:
    table = _table(
        f"reader throughput ({result['data']['kind']} data, read_match)",
        ["files", "failed", "rounds", "MB xz", "MB JSON", "s per file", "MB/s JSON", "MB/s xz"],
        caption=f"peak memory {result['peak_rss_mb']:.0f} MB",
    )
    if not result["files"]:
        table.add_row("0", str(result["failed"]), *("–" * 6))
        return table
    table.add_row(
        str(result["files"]),
        str(result["failed"]),
        str(result["rounds"]),
        f"{result['compressed_mb']:.1f}",
        f"{result['decompressed_mb']:.1f}",
        f"{result['s_per_file_median']:.3f} ({result['s_per_file_min']:.3f}-"
        f"{result['s_per_file_max']:.3f})",
        f"{result['mb_per_s_decompressed']:.1f}",
        f"{result['mb_per_s_compressed']:.2f}",
    )
    return table


def _awpy_table(result: AwpyResult) -> Table:
    table = _table(
        f"awpy readers: the sample's rounds repeated to {result['rounds']}, 64 tick rows a "
        "second, read at the default frame rate, each in a fresh process",
        ["reader", "rounds", "tick rows", "seconds", "rows/s", "peak memory MB"],
    )
    for name, read in result["readers"].items():
        table.add_row(
            name,
            str(read["rounds"]),
            f"{read['rows']:,}",
            f"{read['seconds']:.2f}",
            f"{read['rows_per_s']:,.0f}",
            f"{read['peak_rss_mb']:.0f}",
        )
    return table
