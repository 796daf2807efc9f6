"""Write a comparison of two runs: `compare.csv`, `differences.csv`, `places.csv`,
`differences.png` and `compare.md` (decoy_cli/evaluate/compare.py computes them)."""

from __future__ import annotations

from pathlib import Path

from decoy_cli.evaluate.compare import Comparison
from decoy_cli.evaluate.markdown import interval, md_code, md_table, num, p_value
from decoy_cli.figures import save_figure
from decoy_cli.files import write_atomic, write_csv
from decoy_cli.text import visible

PLACES_SHOWN = 10
"""Nav places listed in compare.md (places.csv has them all)."""


def write_comparison(comparison: Comparison, out: Path) -> list[Path]:
    """Write every output of the comparison into `out`; returns their paths."""
    written = [
        write_csv(out / name, frame)
        for name, frame in (
            ("compare.csv", comparison.table),
            ("differences.csv", comparison.differences),
            ("places.csv", comparison.places),
        )
    ]
    figure = out / "differences.png"
    draw_differences(comparison, figure)
    written.append(figure)
    text = visible(compare_markdown(comparison), keep="\n")
    written.append(write_atomic(out / "compare.md", text.encode()))
    return written


def draw_differences(comparison: Comparison, path: Path) -> None:
    """Box plots of the paired differences B − A per metric, with the zero line."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    metrics = list(comparison.table["metric"])
    data = [comparison.differences[m].to_numpy() for m in metrics]
    fig, ax = plt.subplots(figsize=(9, 0.45 * len(metrics) + 1.5))
    ax.boxplot(data, orientation="horizontal", showfliers=False)
    ax.set_yticks(range(1, len(metrics) + 1), metrics)
    ax.axvline(0.0, color="black", lw=0.8)
    ax.invert_yaxis()
    ax.set_xlabel("B − A per player-round (m; left of zero: B is closer to the data)")
    ax.set_title(f"paired differences, {len(comparison.differences)} player-rounds")
    save_figure(fig, path)


def compare_markdown(comparison: Comparison) -> str:
    """compare.md: what was paired, the metric table and the largest changes by place."""
    rows = [
        [
            f"`{r.metric}`",
            num(r.mean_a),
            num(r.mean_b),
            f"{r.mean_difference:+.3f}",
            interval(r.low, r.high),
            f"{100 * r.improved_share:.1f}% / {100 * r.worse_share:.1f}%",
            p_value(r.wilcoxon_p),
            str(r.note),
        ]
        for r in comparison.table.itertuples()
    ]
    header = [
        "metric",
        "mean A",
        "mean B",
        "B − A",
        "95% interval",
        "better / worse",
        "Wilcoxon p",
        "note",
    ]
    parts = [
        "# Paired comparison of two evaluation runs",
        f"A: {md_code(str(comparison.a.folder))}; B: {md_code(str(comparison.b.folder))}.",
        f"{len(comparison.differences)} player-rounds of {comparison.rounds} rounds paired, "
        "read from the same content in both runs; "
        f"{comparison.only_a} evaluated only in A, {comparison.only_b} only in B (left out)."
        + (
            f" Only one run computed {', '.join(comparison.dropped)}: left out."
            if comparison.dropped
            else ""
        ),
        "Metres; lower is better. The interval is a 95% bootstrap of the mean difference that "
        "resamples whole rounds; better / worse: the share of player-rounds where B is closer "
        "/ farther than A; Wilcoxon: two-sided signed-rank test of the differences.",
        md_table(header, rows),
        "![paired differences](differences.png)",
    ]
    places = comparison.places.head(PLACES_SHOWN)
    if len(places):
        place_rows = [
            [str(r.place), num(r.mean_error_a_m), num(r.mean_error_b_m), f"{r.difference_m:+.3f}"]
            for r in places.itertuples()
        ]
        parts.append(
            "## By nav place (largest changes; all in `places.csv`)\n\n"
            + md_table(["place", "error A (m)", "error B (m)", "B − A (m)"], place_rows)
        )
    return "\n\n".join(parts) + "\n"
