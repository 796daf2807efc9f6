"""The bomb in words: the report's bomb section and the rows the terminal shows of it."""

from __future__ import annotations

from pathlib import Path

from decoy_cli.evaluate.markdown import first_rows, interval, md_inline, md_table, num
from decoy_cli.evaluate.tables import Tables
from decoy_cli.metrics import BombMetrics

BOMB_HEADER = ["metric", "value", "95% interval", "rounds", "over / why not"]


def bomb_rows(bomb: BombMetrics) -> list[list[str]]:
    """One row per bomb metric: name, value, its 95% interval, rounds it is over, and why the
    value or the interval is missing."""
    return [
        [str(r.metric), num(r.value), interval(r.low, r.high), str(r.rounds), str(r.note)]
        for r in bomb.table().itertuples()
    ]


def bomb_section(tables: Tables) -> str:
    """The report's "The bomb" section: the metrics, the plant and defuse confusions, and the
    rounds whose bomb data has anomalies."""
    bomb = tables.bomb
    text = ["## The bomb"]
    if bomb is None:
        return "\n\n".join([*text, "The bomb was off (`--no-bomb`): nothing to compare."])
    text.append(
        f"Over the {bomb.n_rounds} rounds whose data records the bomb; definitions in "
        "docs/metrics.md. Time errors are replay − data in seconds on the round's clock (the "
        "median signed, the mean and p95 of the absolute value); a plant time the data derives "
        "from its frames is known to a frame interval (`plant_time_resolution_s` in "
        "`rounds.csv`)."
    )
    rows = [[f"`{row[0]}`", *row[1:]] for row in bomb_rows(bomb)]
    text.append(md_table(BOMB_HEADER, rows))
    for title, matrix in (("plant", bomb.plant_confusion), ("defuse", bomb.defuse_confusion)):
        header = ["data \\ replay", *map(str, matrix.columns)]
        cells = [[str(i), *map(str, matrix.loc[i])] for i in matrix.index]
        text.append(f"Confusion of the {title} (rows: data):\n\n" + md_table(header, cells))
    rounds = tables.rounds
    odd = rounds[rounds["bomb_anomalies"].fillna("").astype(str) != ""]
    if len(odd):
        text.append(
            f"{len(odd)} rounds have anomalies in their bomb data; they were replayed, and "
            "the `bomb_anomalies` column of `rounds.csv` names them:"
        )
        listed = [
            [md_inline(Path(str(r.file)).name), str(r.round), md_inline(str(r.bomb_anomalies))]
            for r in odd.itertuples()
        ]
        text.append(first_rows(["file", "round", "anomalies"], listed, "rounds.csv"))
    else:
        text.append("No anomaly in the bomb data.")
    return "\n\n".join(text)
