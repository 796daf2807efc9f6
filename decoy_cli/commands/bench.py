"""`decoy bench`: the paper's Table 1 and the throughput of replay, metrics and reader."""

from __future__ import annotations

from pathlib import Path
from typing import cast

import typer
from rich.console import Console
from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeElapsedColumn
from rich.table import Table
from rich.text import Text

from decoy_cli.bench import (
    SECTIONS,
    BenchConfig,
    BenchData,
    check_damage_model,
    failed_sections,
    find_data,
    machine_info,
    report,
    run_isolated,
)
from decoy_cli.bench.baseline import baseline_tree, current_tree, side_by_side
from decoy_cli.bench.records import (
    BenchSwitches,
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
from decoy_cli.commands._console import make_console
from decoy_cli.commands._options import MAPS_HELP, models_option, mover_option
from decoy_cli.csgo import BUILTIN_MAP
from decoy_cli.damage import SHIPPED_CHOICES, ModelName, parse_models
from decoy_cli.errors import DecoyError, OutputError
from decoy_cli.files import check_writable, write_json
from decoy_cli.sim.setup import MoverName

DEFAULT_OUT = Path("decoy-out") / "bench" / "bench.json"

TITLES = {
    "table1": "Table 1: simulator speed",
    "kinematic": "kinematic core, Table 1 at 10 agents",
    "env": "environment, 5v5",
    "combat_step": "one 5v5 combat step",
    "replay": "replay throughput",
    "metrics": "metric throughput",
    "reader": "reader throughput",
}


def bench(
    quick: bool = typer.Option(
        False,
        "--quick",
        help="A smoke run of a few seconds per section: 1,000 decisions at 2 and 10 agents, "
        "3 rounds, 100 metric pairs, 2 files.",
    ),
    models: str = models_option(ModelName.SHIPPED),
    data: Path | None = typer.Option(
        None,
        "--data",
        help="Folder of ESTA match files for the replay and reader sections (default: "
        "../shared/data/esta_dust2_tside when present, else the sample in examples/sample/).",
    ),
    mover: MoverName = mover_option("physics"),
    combat: bool = typer.Option(
        True,
        "--combat/--no-combat",
        help="The combat step in Table 1 and shooting in the replay section (the paper's "
        "Table 1 has it on).",
    ),
    bomb: bool = typer.Option(
        True, "--bomb/--no-bomb", help="Bomb rules in Table 1 and in the replay section."
    ),
    out: Path = typer.Option(DEFAULT_OUT, "--out", help="The JSON report."),
    seed: int = typer.Option(0, "--seed", help="Seed of agent placements and actions."),
    map_name: str = typer.Option(
        "dust2",
        "--map",
        help=f"Built-in map of Table 1, the kinematic, env and combat-step sections ({MAPS_HELP}; "
        "replay and reader use the data's files).",
    ),
    sections: str = typer.Option(
        ",".join(SECTIONS), "--sections", help="Comma-separated sections to run."
    ),
    baseline: str | None = typer.Option(
        None,
        "--baseline",
        help="Measure the speed-up against a baseline in the same run: a git ref of this "
        "checkout (e.g. HEAD~3, a tag) or the Python interpreter of another environment. Each "
        "section runs --repeats times on each side, alternating, in fresh processes; the table "
        "gives the ratio (median, min, max).",
    ),
    repeats: int = typer.Option(
        3, "--repeats", min=1, help="Runs per side of each section with --baseline."
    ),
) -> None:
    """Measure the simulator's speed (the paper's Table 1) and the throughput of the pipeline.

    Sections: Table 1, a 5v5 combat step, replay, metrics and reader throughput, each in its
    own process; prints tables and writes a JSON report with the machine. Exits non-zero when a
    section failed.

    --mover is Table 1's (physics by default, as the paper's). --models is the combat step's:
    if the models cannot be loaded, the benchmark says so and runs line of sight without
    inference. Its default is the DOG (shipped), not the rules that `replay` and `evaluate`
    default to: every earlier version has it, so `--baseline` compares like with like."""
    console = make_console()
    if out.is_dir():
        raise OutputError(f"--out {out}: is a folder; give the JSON file to write")
    check_writable(out)  # before minutes of measuring
    chosen = _chosen_sections(sections)
    choice = parse_models(models)
    config = BenchConfig.create(
        quick=quick,
        models=choice,
        mover=mover,
        combat=combat,
        bomb=bomb,
        seed=seed,
        map_name=map_name,
    )
    bench_data = find_data(data)
    machine = machine_info()
    console.print(_machine_line(machine), highlight=False)
    if baseline is not None:
        switches: BenchSwitches = {
            "quick": quick,
            "models": str(choice),
            "mover": mover,
            "combat": combat,
            "bomb": bomb,
            "seed": seed,
        }
        if config.map_name != BUILTIN_MAP:  # only then: earlier versions know no --map
            switches["map_name"] = config.map_name
        _side_by_side(console, chosen, switches, bench_data, baseline, repeats, out)
        return
    status = check_damage_model(choice)
    if status.error:
        console.print(
            f"damage model {models!r} could not be loaded: {status.error}"
            "\nfalling back to line of sight without inference (labelled in the tables)",
            style="yellow",
        )
    console.print(f"damage model: {status.label}", highlight=False)
    console.print(
        "data: "
        + (
            f"{bench_data.kind}, {len(bench_data.files)} files in {bench_data.folder}"
            if bench_data
            else "none found (replay and reader sections skipped)"
        ),
        highlight=False,
    )
    results: dict[str, SectionResult] = {}
    with Progress(
        TextColumn("{task.description}", markup=False),
        BarColumn(),
        MofNCompleteColumn(),
        TimeElapsedColumn(),
        console=console,
        transient=True,
    ) as progress:
        task = progress.add_task("bench", total=len(chosen))
        for name in chosen:
            progress.update(task, description=TITLES[name])
            results[name] = run_isolated(name, config, status, bench_data)
            progress.console.print(_render(name, results[name]))
            progress.advance(task)
    document = report(config, status, bench_data, results, machine)
    write_json(out, document, sort_keys=False)
    console.print(
        f"peak memory of this process {document['peak_rss_mb_main']:.0f} MB; load average at "
        f"the end {_load(document['load_average_end'])}; "
        f"report written to {out}",
        highlight=False,
    )
    failed = failed_sections(results)
    if failed:
        make_console(stderr=True).print(
            f"error: {len(failed)} section(s) failed: {', '.join(failed)}", highlight=False
        )
        raise typer.Exit(1)


def _chosen_sections(text: str) -> list[str]:
    names = [name.strip() for name in text.split(",") if name.strip()]
    unknown = [name for name in names if name not in SECTIONS]
    if unknown or not names:
        raise DecoyError(
            f"--sections {text!r}: unknown {', '.join(unknown) or '(none given)'}; "
            f"the sections are {', '.join(SECTIONS)}"
        )
    return [name for name in SECTIONS if name in names]


def _side_by_side(
    console: Console,
    chosen: list[str],
    config: BenchSwitches,
    bench_data: BenchData | None,
    ref: str,
    repeats: int,
    out: Path,
) -> None:
    """Run the sections on this code and on the baseline, alternating; print the ratios.
    Paths are made absolute: the runs start in folders of their own."""
    work = out.resolve().parent
    work.mkdir(parents=True, exist_ok=True)
    models = config["models"]
    if models not in (*SHIPPED_CHOICES, "none"):  # a folder, as the loader reads it
        config = {**config, "models": str(Path(models).resolve())}
    data = bench_data.folder.resolve() if bench_data else None
    with baseline_tree(ref, work) as baseline:
        console.print(
            f"side by side: current code against {baseline.label}, {repeats} runs each, "
            f"alternating; data: {data or 'none (replay and reader skipped)'}",
            highlight=False,
        )
        with Progress(
            TextColumn("{task.description}", markup=False),
            TimeElapsedColumn(),
            console=console,
            transient=True,
        ) as progress:
            task = progress.add_task("")
            result = side_by_side(
                chosen,
                config,
                data,
                current_tree(),
                baseline,
                repeats,
                work,
                on_run=lambda section, side, k: progress.update(
                    task, description=f"{TITLES[section]}: {side}, run {k + 1} of {repeats}"
                ),
            )
    console.print(_ratio_table(result))
    write_json(out, {"machine": machine_info(), "side_by_side": result}, sort_keys=False)
    console.print(f"report written to {out}", highlight=False)
    if result["errors"]:
        for line in result["errors"]:
            make_console(stderr=True).print(f"error: {line}", highlight=False)
        raise typer.Exit(1)


def _ratio_table(result: SideBySide) -> Table:
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


def _machine_line(machine: MachineInfo) -> str:
    packages = machine["packages"]
    versions = ", ".join(
        f"{name} {packages[name]}" for name in ("numpy", "torch", "pybullet") if packages[name]
    )
    memory = f", {machine['memory_gb']:.0f} GB" if machine["memory_gb"] else ""
    return (
        f"machine: {machine['cores']} cores ({machine['usable_cores']} usable), "
        f"{machine['cpu']}{memory}; python {machine['python']}, {versions}; "
        f"load average {_load(machine['load_average'])}"
    )


def _load(load: list[float] | None) -> str:
    return f"{load[0]:.2f} (1 min)" if load else "unknown"


def _render(name: str, result: SectionResult) -> Table | Text:
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
        "one 5v5 combat step, median ms",
        ["layout", "steps", "line of sight", "batch", "model", "damage", "step", "visible pairs"],
        caption=f"damage model: {result['damage_model']}; peak memory "
        f"{result['peak_rss_mb']:.0f} MB",
    )
    for row in result["rows"]:
        parts = row["parts"]
        table.add_row(
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


def _metrics_table(result: MetricsResult) -> Table:
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
    return table


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
