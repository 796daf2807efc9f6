"""`decoy compare RUN_A RUN_B`: the paired comparison of two `decoy evaluate` runs."""

from __future__ import annotations

from pathlib import Path

import typer
from rich.table import Table

from decoy_cli.commands._console import make_console
from decoy_cli.evaluate.compare import compare_runs, read_run
from decoy_cli.evaluate.compare_outputs import write_comparison
from decoy_cli.evaluate.markdown import interval, num, p_value
from decoy_cli.files import check_folder_writable


def compare(
    run_a: Path = typer.Argument(..., help="Output folder of a `decoy evaluate` run (A)."),
    run_b: Path = typer.Argument(..., help="Output folder of a run of the same data (B)."),
    out: Path = typer.Option(
        Path("decoy-out/compare"), "--out", help="Where to write compare.md and the tables."
    ),
    seed: int = typer.Option(0, "--seed", help="Seed of the bootstrap intervals."),
) -> None:
    """Pair the player-rounds two runs evaluated and say, per metric, how much B changed them:
    the mean difference B − A with its 95% interval (by round), the share improved, and a
    Wilcoxon signed-rank p-value; by nav place too. Runs of different data cannot be paired."""
    console = make_console()
    comparison = compare_runs(read_run(run_a), read_run(run_b), seed=seed)
    check_folder_writable(out)
    write_comparison(comparison, out)
    console.print(
        f"{len(comparison.differences)} player-rounds of {comparison.rounds} rounds paired "
        f"({comparison.only_a} only in A, {comparison.only_b} only in B); metres, lower is better"
        + (
            f"; only one run has {', '.join(comparison.dropped)}: left out"
            if comparison.dropped
            else ""
        )
    )
    table = Table(title="B − A")
    for column in ("metric", "mean A", "mean B", "B − A", "95% interval", "better", "worse", "p"):
        table.add_column(column, justify="left" if column == "metric" else "right")
    for r in comparison.table.itertuples():
        table.add_row(
            str(r.metric),
            num(r.mean_a),
            num(r.mean_b),
            f"{r.mean_difference:+.3f}",
            interval(r.low, r.high),
            f"{100 * r.improved_share:.1f}%",
            f"{100 * r.worse_share:.1f}%",
            p_value(r.wilcoxon_p),
        )
    console.print(table)
    console.print(f"comparison written to {out} (report: {out / 'compare.md'})")
