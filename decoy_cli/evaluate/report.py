"""The evaluation in words: `report.md`, and the descriptions the terminal shares with it.

What data was evaluated (`data_kind`), what the simulation did (`mechanics`), the command that
reruns it (`command_line`), the trajectory and combat sections with their caveats, the figures
and the failures; decoy_cli/evaluate/outputs.py writes it with the tables.
"""

from __future__ import annotations

import math
import shlex
from collections import Counter
from collections.abc import Sequence
from dataclasses import dataclass
from functools import cache
from pathlib import Path
from typing import TYPE_CHECKING

from decoy_cli.esta.frame_rate import describe_rates
from decoy_cli.evaluate.bomb_report import bomb_section
from decoy_cli.evaluate.data_notes import (
    contradictions_section,
    inferred_section,
    warnings_section,
)
from decoy_cli.evaluate.markdown import first_rows, interval, md_code, md_inline, md_table, num
from decoy_cli.evaluate.runner import Evaluation
from decoy_cli.evaluate.settings import EvalSettings
from decoy_cli.evaluate.tables import Tables
from decoy_cli.metrics import (
    FASTDTW_METRIC,
    GROUPS,
    METRIC_NAMES_CLOCK,
    METRIC_NAMES_PAPER,
    PAPER_PROTOCOL_NAMES,
    SIDES,
)
from decoy_cli.metrics.bootstrap import MIN_ROUNDS, RESAMPLES
from decoy_cli.metrics.fastdtw_metric import FASTDTW_RTOL

if TYPE_CHECKING:
    from decoy_cli.waypoints.build import GameWorld


@dataclass(frozen=True)
class RunInfo:
    """How the run was started, for the report: the command line, where it ran, the sample."""

    command: str
    backend: str
    """e.g. "2 local worker processes" or "Dask scheduler tcp://10.0.0.1:8786"."""
    sample: int | None
    machine: str


def data_kind(evaluation: Evaluation) -> str:
    """ "synthetic", "real" or "mixed", from the files' metadata (no file: "none")."""
    flags = {f.index.synthetic for f in evaluation.files if f.index is not None}
    if not flags:
        return "none"
    if flags == {True}:
        return "synthetic"
    return "real" if flags == {False} else "mixed"


def mechanics(settings: EvalSettings) -> str:
    """What the simulation did, in words."""
    if not settings.combat and not settings.bomb:
        return "movement only: combat and bomb off (as in the paper's Table 2); deaths scripted"
    bomb = "bomb on" if settings.bomb else "bomb off"
    if not settings.combat:
        return f"combat off, {bomb}: deaths scripted from the data"
    if settings.models_fingerprint:
        deaths = (
            "deaths decided by the simulated fight"
            if settings.deaths == "simulated"
            else "deaths from the data (the paper's protocol; shooting wounds, does not kill)"
        )
        return f"combat (damage model: {settings.models}; {deaths}), {bomb}"
    return f"{bomb}, no shooting (--models none): deaths scripted from the data"


def model_lines(settings: EvalSettings) -> dict[str, str]:
    """ "hits decided by" and "damage decided by", in words (`damage.model_roles`)."""
    from decoy_cli.damage import ModelName, model_roles
    from decoy_cli.damage.model_maps import map_warnings

    models = settings.models if settings.combat else ModelName.NONE
    roles = model_roles(models)
    lines = {"hits decided by": roles["hits"], "damage decided by": roles["damage"]}
    warnings = map_warnings(models, [settings.map_name]) if settings.models_fingerprint else []
    if warnings:
        lines["model warnings"] = "; ".join(warnings)
    return lines


def world_line(settings: EvalSettings) -> str:
    """The world the rounds replay on, in words, and why that one."""
    source = _world_source(settings.map_name, settings.shipped_world, settings.graph) or "unnamed"
    if settings.graph:
        return f"{source}, from the graph {settings.graph}"
    if settings.world == "cs2":
        return f"{source} (the CS2 world the package ships for {settings.map_name})"
    return f"{source} (the CS:GO world of {settings.map_name})"


@cache
def _world_source(map_name: str, world: GameWorld, graph: str) -> str:
    """Where the world of a run's graph comes from (the console, report.md and summary.json
    each say it: the graph is read once)."""
    from decoy_cli.waypoints.build import builtin_graph
    from decoy_cli.waypoints.graph import WaypointGraph

    if graph:
        return WaypointGraph.load(graph).world_source
    return builtin_graph(map_name, world).world_source


def sight_line(settings: EvalSettings) -> str | None:
    """Where line of sight was tested, in words (None without shooting)."""
    if not settings.models_fingerprint:
        return None
    if settings.sight_mesh:
        return f"{settings.sight_mesh} (sha256 {settings.sight_mesh_sha[:12]})"
    return (
        "the nav world the graph was built on (approximate: no windows, props or low cover; "
        "--sight-mesh gives the map's geometry)"
    )


def command_line(
    inputs: Sequence[Path], settings: EvalSettings, sample: int | None, out: Path
) -> str:
    """The command with every effective option (what a reader needs to rerun it)."""
    words = ["decoy", "evaluate", *map(str, inputs), "--map", settings.map_name]
    if settings.graph:
        words += ["--graph", settings.graph]
    else:
        words += ["--world", settings.world]
    if settings.sight_mesh:
        words += ["--sight-mesh", settings.sight_mesh]
    if sample is not None:
        words += ["--sample", str(sample)]
    words += ["--seed", str(settings.seed), "--combat" if settings.combat else "--no-combat"]
    words += ["--bomb" if settings.bomb else "--no-bomb"]
    if settings.combat:
        words += ["--models", str(settings.models), "--deaths", settings.deaths]
    words += ["--mover", settings.mover, "--implausible", settings.implausible]
    words += ["--missing-fields", settings.missing]
    words += ["--fastdtw" if settings.fastdtw else "--no-fastdtw", "--out", str(out)]
    return shlex.join(words)


def run_counts(evaluation: Evaluation, tables: Tables) -> dict[str, int]:
    return {
        "match_files": len(evaluation.files),
        "ignored_files": len(evaluation.ignored),
        "duplicate_files": len(evaluation.duplicates),
        "rounds_available": evaluation.rounds_available,
        "rounds_planned": evaluation.rounds_planned,
        "rounds_evaluated": evaluation.accumulator.rounds,
        "rounds_from_cache": evaluation.cached,
        "rounds_computed": evaluation.computed,
        "rounds_both_teams": tables.rounds_both_teams,
        "rounds_with_winner": tables.rounds_with_winner,
        "player_rounds": len(tables.players),
        "failures": len(evaluation.failures),
        "rounds_with_warnings": tables.rounds_with_warnings,
        "rounds_with_contradictions": tables.rounds_with_contradictions,
        "rounds_with_inferred_fields": tables.rounds_with_inferred,
    }


def table_groups(tables: Tables) -> list[str]:
    """The groups a trajectory table shows: each side in the data, and all when both are."""
    sides = [g for g in SIDES if tables.summary.n_evaluated[g]]
    return [*sides, "all"] if len(sides) != 1 else sides


def protocols(tables: Tables) -> list[tuple[str, tuple[str, ...]]]:
    """The metrics of each protocol this run computed (`paper_dtw_fastdtw` only on request)."""
    paper: tuple[str, ...] = METRIC_NAMES_PAPER
    if FASTDTW_METRIC in tables.players.columns:
        paper = PAPER_PROTOCOL_NAMES
    return [("clock", METRIC_NAMES_CLOCK), ("paper", paper)]


def fastdtw_note(tables: Tables) -> str:
    """What `paper_dtw_fastdtw` is, and how often its per-step mean fell below the exact one."""
    evaluated = tables.players[tables.players["reason"].isna()]
    # below by more than rounding (the two sum a point's coordinates in different orders)
    exact = evaluated["paper_dtw"]
    below = int((evaluated[FASTDTW_METRIC] < exact * (1 - FASTDTW_RTOL)).sum())
    return (
        f"`{FASTDTW_METRIC}` is the paper's own computation: FastDTW (the `fastdtw` package, "
        "radius 1, Euclidean point cost) on the resampled trajectories, its total cost over its "
        "path's length. FastDTW's total cost is never below the exact DTW's minimum (up to "
        "rounding); its "
        f"per-step mean fell below the exact `paper_dtw` in {below} of {len(evaluated)} "
        "player-rounds (where its path is longer)."
    )


def trajectory_rows(tables: Tables, names: tuple[str, ...]) -> tuple[list[str], list[list[str]]]:
    """Header and rows of one protocol's table: mean ± std, median, p90 of each `table_groups`
    group, and the paper's Table 2 for the same groups."""
    groups = table_groups(tables)
    stats = tables.trajectory.set_index(["metric", "group"])
    header = ["metric"]
    for group in groups:
        header += [f"{group} mean ± std", f"{group} median", f"{group} p90"]
    paper_groups = groups if any(n in PAPER_PROTOCOL_NAMES for n in names) else []
    header += [f"paper {g}" for g in paper_groups]
    rows = []
    for name in names:
        row = [name]
        for group in groups:
            s = stats.loc[(name, group)]
            row += [
                f"{num(s['mean'])} ± {num(s['std'])} {interval(s['mean_low'], s['mean_high'])}",
                f"{num(s['median'])} {interval(s['median_low'], s['median_high'])}",
                num(s["p90"]),
            ]
        for group in paper_groups:
            s = stats.loc[(name, group)]
            row.append(
                "–"
                if math.isnan(s["paper_mean"])
                else f"{s['paper_mean']:.3f} ± {s['paper_std']:.3f}"
            )
        rows.append(row)
    return header, rows


def _provenance_line(evaluation: Evaluation) -> str | None:
    """What the files say about where they come from (their top-level `provenance`)."""
    stated = [f.index.provenance for f in evaluation.files if f.index and f.index.provenance]
    if not stated:
        return None
    first = stated[0] if len(stated[0]) <= 400 else stated[0][:400] + " …"
    return (
        f"Provenance stated by {len(stated)} of {len(evaluation.files)} match files "
        f"({len(set(stated))} distinct); the first: {md_code(first)}"
    )


def _count(count: int, noun: str) -> str:
    return f"{count} {noun}" + ("" if count == 1 else "s")


def _data_line(evaluation: Evaluation) -> str:
    kind = data_kind(evaluation)
    if kind == "synthetic":
        return (
            "**Data: synthetic.** Every match file says it was generated by the project "
            "(not recorded in a real match): these numbers check the pipeline, not reality."
        )
    if kind == "mixed":
        synthetic = sum(1 for f in evaluation.files if f.index is not None and f.index.synthetic)
        return (
            f"**Data: mixed**: {synthetic} of {len(evaluation.files)} match files are synthetic "
            "(generated by the project); the numbers mix generated and real rounds."
        )
    if kind == "real":
        return "**Data: real** recorded matches (no file says it is synthetic)."
    return "**Data: none** could be read."


def report_markdown(
    evaluation: Evaluation, tables: Tables, info: RunInfo, figures: dict[str, Path]
) -> str:
    """The whole report (see the module docstring)."""
    settings = evaluation.settings
    counts = run_counts(evaluation, tables)
    computed = f"{evaluation.computed} computed"
    if evaluation.computed:
        rate = evaluation.computed / evaluation.compute_seconds
        computed += f" in {evaluation.compute_seconds:.1f} s ({rate:.2f} rounds/s)"
    parts = [f"# DECOY replay fidelity on {settings.map_name}", _data_line(evaluation)]
    provenance = _provenance_line(evaluation)
    if provenance:
        parts.append(provenance)
    run_rows = [
        ["command", md_code(info.command)],
        ["inputs", ", ".join(md_code(str(p)) for p in evaluation.inputs)],
        [
            "match files",
            f"{counts['match_files']} ({_count(counts['ignored_files'], 'other file')} "
            f"ignored, {_count(counts['duplicate_files'], 'duplicate')} skipped)",
        ],
        [
            "rounds",
            f"{counts['rounds_evaluated']} evaluated of {counts['rounds_available']} "
            f"{settings.map_name} rounds"
            + (f" (a sample of {info.sample}, seed {settings.seed})" if info.sample else ""),
        ],
        ["computed / from cache", f"{computed}, {evaluation.cached} from the cache"],
        ["failures", f"{counts['failures']} (see below and `failures.csv`)"],
        [
            "implausible data",
            f"rounds {'replayed with warnings' if settings.implausible == 'warn' else 'fail'} "
            f"(`--implausible {settings.implausible}`): "
            f"{counts['rounds_with_warnings']} rounds with warnings",
        ],
        [
            "fields the data lacks",
            f"`--missing-fields {settings.missing}`: "
            f"{counts['rounds_with_inferred_fields']} rounds with fields filled by rule "
            "(below, and the `inferred` column of `rounds.csv`)",
        ],
        ["mechanics", mechanics(evaluation.settings)],
        ["world", world_line(settings)],
        *([name, text] for name, text in model_lines(settings).items()),
        *([["line of sight in", sight]] if (sight := sight_line(settings)) else []),
        ["mover, seed", f"{settings.mover}, {settings.seed}"],
        ["ran on", f"{info.backend}; {info.machine}"],
        ["wall time", f"{evaluation.wall_seconds:.1f} s (before writing the outputs)"],
        [
            "rounds with both teams",
            f"{counts['rounds_both_teams']} of {counts['rounds_evaluated']}",
        ],
        ["player-rounds", str(counts["player_rounds"])],
        ["frame rate of the data", describe_rates(tables.rounds["frame_rate"].to_numpy(float))],
    ]
    parts.append("## What was run\n\n" + md_table(["", ""], run_rows))
    parts.append(_trajectory_section(tables, settings))
    parts.append(_combat_section(tables, settings))
    parts.append(bomb_section(tables))
    parts.append(_figures_section(tables, figures))
    parts.append(_failures_section(evaluation))
    if counts["rounds_with_warnings"]:
        parts.append(warnings_section(tables))
    if counts["rounds_with_contradictions"]:
        parts.append(contradictions_section(tables))
    if counts["rounds_with_inferred_fields"]:
        parts.append(inferred_section(tables))
    return "\n\n".join(parts) + "\n"


def _trajectory_section(tables: Tables, settings: EvalSettings) -> str:
    on = [name for name, flag in (("combat", settings.combat), ("bomb", settings.bomb)) if flag]
    text = [
        "## Trajectory fidelity (the paper's Table 2)",
        "Metres; definitions in docs/metrics.md. Protocol *clock* compares original and replay "
        "frame by frame on the common clock; protocol *paper* resamples each alive trajectory "
        "to 451 points first, as the paper's evaluation did; the paper's values sit beside it"
        + (
            f" (the paper ran movement only; this run had {' and '.join(on)} on)."
            if on
            else " (movement only there and here)."
        ),
    ]
    for title, names in protocols(tables):
        header, rows = trajectory_rows(tables, names)
        rows = [[f"`{row[0]}`", *row[1:]] for row in rows]
        text.append(f"### Protocol {title}\n\n" + md_table(header, rows))
    if FASTDTW_METRIC in tables.players.columns:
        text.append(fastdtw_note(tables))
    summary = tables.summary
    evaluated = ", ".join(
        f"{g}: {summary.n_evaluated[g]} of {summary.n_rows[g]}" for g in GROUPS if summary.n_rows[g]
    )
    text.append(f"Player-rounds evaluated: {evaluated or 'none'}.")
    text.append(
        f"In brackets: 95% bootstrap intervals of the mean and the median that resample whole "
        f"rounds ({RESAMPLES} resamples, seed {settings.seed}; none over fewer than "
        f"{MIN_ROUNDS} rounds)."
    )
    if len(summary.unevaluated):
        rows = [[r.group, r.reason, str(r.count)] for r in summary.unevaluated.itertuples()]
        text.append("Not evaluated:\n\n" + md_table(["group", "reason", "player-rounds"], rows))
    return "\n\n".join(text)


def combat_caveats(tables: Tables, settings: EvalSettings) -> list[str]:
    """What the HP, death and outcome numbers do not measure in this run (report and terminal)."""
    caveats = []
    if settings.combat and settings.deaths == "simulated":
        caveats.append(
            "Deaths were decided by the simulated fight (--deaths simulated): a player the "
            "fight had not killed 3 s after his real death was taken out then, and such deaths "
            "count as died only in the data (death times, recall). The paper's HP, death and "
            "outcome figures come from deaths that follow the data: compare them with a "
            "--deaths data run."
        )
    elif settings.combat:
        caveats.append(
            "Deaths followed the data (--deaths data, the paper's protocol): death times and "
            "outcomes measure the scripting and the bomb, HP the wounds."
        )
    if not settings.combat:
        caveats.append(
            "Combat was off: HP changes only where a death is scripted from the data, so these "
            "measure the scripting, not a damage model."
        )
    if tables.rounds_both_teams == 0:
        caveats.append(
            "No evaluated round has both teams in its data: the paper's numbers are for full "
            "rounds and are not comparable here."
        )
    return caveats


def _combat_section(tables: Tables, settings: EvalSettings) -> str:
    text = ["## HP, deaths and outcomes", *combat_caveats(tables, settings)]
    rows = [
        [
            f"`{r.metric}`",
            num(r.value),
            interval(r.low, r.high),
            str(r.n),
            num(r.paper),
            str(r.note) + (f"; {r.interval_note}" if r.interval_note else ""),
        ]
        for r in tables.combat.itertuples()
    ]
    header = ["metric", "value", "95% interval", "n", "paper", "over / why not"]
    text.append(md_table(header, rows))
    counts = tables.deaths.counts
    text.append(
        "Deaths: "
        + ", ".join(f"{name.replace('_', ' ')} {value}" for name, value in counts.items())
        + "."
    )
    if tables.outcome is None:
        text.append("Outcomes: no round has its winner recorded in the data.")
    else:
        for title, matrix in (
            ("winner", tables.outcome.winner_confusion),
            ("end reason", tables.outcome.end_reason_confusion),
        ):
            if matrix is None:
                continue
            header = ["original \\ replay", *map(str, matrix.columns)]
            rows = [[str(i), *map(str, matrix.loc[i])] for i in matrix.index]
            text.append(f"Confusion of the {title} (rows: data):\n\n" + md_table(header, rows))
    return "\n\n".join(text)


PLACE_COLUMNS = [
    "place",
    "original",
    "replay",
    "difference (pp)",
    "mean distance (m)",
    "off the graph",
]

PLACE_CAPTION = (
    "By nav place (the place of the nearest waypoint), largest error first, with the share of "
    "the player's samples that have no waypoint on their floor (where the replay cannot follow):"
)


def _figures_section(tables: Tables, figures: dict[str, Path]) -> str:
    """The figures with their captions and the table by nav place; the table alone when no
    figure was drawn."""
    rows = [
        [
            str(r.place),
            f"{100 * r.original_share:.1f}%",
            f"{100 * r.replay_share:.1f}%",
            f"{r.difference_pp:+.2f}",
            num(r.mean_error_m, 2),
            f"{100 * r.off_graph_share:.1f}%",
        ]
        for r in tables.places.itertuples()
    ]
    if not figures:
        return "\n\n".join(
            [
                "## Figures",
                f"Not drawn (`--no-figures`). {PLACE_CAPTION}",
                md_table(PLACE_COLUMNS, rows),
            ]
        )
    return "\n\n".join(
        [
            "## Figures",
            "### Where the players and the replay are (the paper's Figure 5)",
            f"![heatmaps]({figures['heatmaps'].as_posix()})",
            "Share of alive samples per 0.5 m cell (smoothed), and the signed percentage "
            "difference replay − original relative to their mean.",
            "### Where the replay is off",
            f"![error map]({figures['error_map'].as_posix()})",
            "The distance between the replayed agent and the player at each data frame (the "
            f"clock protocol's per-frame distance), by where the player was. {PLACE_CAPTION}",
            md_table(PLACE_COLUMNS, rows),
            "### HP over time",
            f"![HP over time]({figures['hp_over_time'].as_posix()})",
            "### Death times",
            f"![death times]({figures['death_times'].as_posix()})",
            "### Final outcomes (the paper's Figure 6)",
            f"![outcomes]({figures['outcomes'].as_posix()})",
        ]
    )


def _failures_section(evaluation: Evaluation) -> str:
    failures = evaluation.failures
    if not failures:
        return "## Failures\n\nNone."
    kinds = Counter(f.kind for f in failures)
    text = [
        "## Failures",
        f"{len(failures)} files or rounds produced no result (all in `failures.csv`): "
        + ", ".join(f"{kind} {count}" for kind, count in kinds.most_common())
        + ".",
    ]
    rows = [
        [
            md_inline(Path(f.file).name),
            "" if f.round_num is None else str(f.round_num),
            f.kind,
            md_inline(f.message),
        ]
        for f in failures
    ]
    text.append(first_rows(["file", "round", "kind", "reason"], rows, "failures.csv"))
    return "\n\n".join(text)
