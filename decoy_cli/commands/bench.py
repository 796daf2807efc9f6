"""`decoy bench`: the paper's Table 1 and the throughput of replay, metrics and reader."""

from __future__ import annotations

from pathlib import Path

import typer
from rich.console import Console
from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeElapsedColumn

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
from decoy_cli.bench.baseline import baseline_tree, current_tree, run_args, side_by_side
from decoy_cli.bench.records import RunArgs, SectionResult
from decoy_cli.commands._bench_tables import (
    TITLES,
    load_text,
    machine_line,
    ratio_table,
    section_table,
)
from decoy_cli.commands._console import make_console
from decoy_cli.commands._options import MAPS_HELP, models_option, mover_option
from decoy_cli.damage import ModelName, parse_models
from decoy_cli.errors import DecoyError, OutputError
from decoy_cli.files import check_writable, write_json
from decoy_cli.sim.setup import MoverName

DEFAULT_OUT = Path("decoy-out") / "bench" / "bench.json"


def bench(
    quick: bool = typer.Option(
        False,
        "--quick",
        help="A smoke run of a few seconds per section: 1,000 decisions at 2 and 10 agents, "
        "20 combat steps, 3 rounds, 100 metric pairs, 2 files.",
    ),
    agents: str | None = typer.Option(
        None,
        "--agents",
        metavar="N,N,...",
        help="Table 1's agent counts, comma-separated (default 2,6,10,20,100, the paper's; "
        "2,10 with --quick).",
    ),
    decisions: int | None = typer.Option(
        None,
        "--decisions",
        min=1,
        help="Agent decisions per row of Table 1 and of the kinematic core (default 10,000, "
        "the paper's; 1,000 with --quick).",
    ),
    combat_agents: str | None = typer.Option(
        None,
        "--combat-agents",
        metavar="N,N,...",
        help="Agent counts of the combat step, even, comma-separated, half T and half CT "
        "(default 10; e.g. 10,100 adds a crowded step, timed over proportionally fewer steps).",
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

    Sections: Table 1, the kinematic core, the environment, the combat step (5v5 unless
    --combat-agents), replay, metrics (and the DTW and Fréchet kernels alone), reader and awpy
    throughput, each in its own process; prints tables and writes a JSON report with the
    machine. Exits non-zero when a section failed.

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
        agent_counts=_counts(agents, "--agents"),
        decisions=decisions,
        combat_agents=_counts(combat_agents, "--combat-agents"),
    )
    bench_data = find_data(data)
    machine = machine_info()
    console.print(machine_line(machine), highlight=False)
    if baseline is not None:
        _side_by_side(console, chosen, run_args(config), bench_data, baseline, repeats, out)
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
            progress.console.print(section_table(name, results[name]))
            progress.advance(task)
    document = report(config, status, bench_data, results, machine)
    write_json(out, document, sort_keys=False)
    console.print(
        f"peak memory of this process {document['peak_rss_mb_main']:.0f} MB; load average at "
        f"the end {load_text(document['load_average_end'])}; "
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


def _counts(text: str | None, option: str) -> list[int] | None:
    """Comma-separated whole numbers (BenchConfig.create checks their range)."""
    if text is None:
        return None
    try:
        counts = [int(part) for part in text.split(",") if part.strip()]
    except ValueError:
        counts = []
    if not counts:
        raise DecoyError(
            f"{option} {text!r}: give whole numbers separated by commas, e.g. 2,10,100"
        )
    return counts


def _side_by_side(
    console: Console,
    chosen: list[str],
    run: RunArgs,
    bench_data: BenchData | None,
    ref: str,
    repeats: int,
    out: Path,
) -> None:
    """Run the sections on this code and on the baseline, alternating; print the ratios.
    Paths are made absolute: the runs start in folders of their own."""
    work = out.resolve().parent
    work.mkdir(parents=True, exist_ok=True)
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
                run,
                data,
                current_tree(),
                baseline,
                repeats,
                work,
                on_run=lambda section, side, k: progress.update(
                    task, description=f"{TITLES[section]}: {side}, run {k + 1} of {repeats}"
                ),
            )
    console.print(ratio_table(result))
    write_json(out, {"machine": machine_info(), "side_by_side": result}, sort_keys=False)
    console.print(f"report written to {out}", highlight=False)
    if result["errors"]:
        for line in result["errors"]:
            make_console(stderr=True).print(f"error: {line}", highlight=False)
        raise typer.Exit(1)
