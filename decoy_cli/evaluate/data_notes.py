"""The report's sections on what a run's data lacked, contradicted or held implausible: the
fields filled by rule, the frames and events that disagree, the implausible data replayed under
`--implausible warn` (each per round in `rounds.csv`)."""

from __future__ import annotations

from pathlib import Path

from decoy_cli.evaluate.markdown import first_rows, md_inline
from decoy_cli.evaluate.record import WARNING_SEPARATOR
from decoy_cli.evaluate.tables import Tables


def contradictions_section(tables: Tables) -> str:
    """The rounds whose frames and events say against each other, replayed as they are."""
    rounds = tables.rounds[tables.rounds["contradictions"] != ""]
    rows = [
        [md_inline(Path(str(row.file)).name), str(row.round), md_inline(str(row.contradictions))]
        for row in rounds.itertuples()
    ]
    return "\n\n".join(
        [
            "## Frames and events that contradict each other",
            f"{len(rounds)} rounds were replayed as their data has them; what does not add up "
            "is in the `contradictions` column of `rounds.csv`.",
            first_rows(["file", "round", "contradictions"], rows, "rounds.csv"),
        ]
    )


def inferred_section(tables: Tables) -> str:
    """The fields the data lacked and the rules that filled them, by how many rounds."""
    notes = tables.rounds["inferred"].str.split(WARNING_SEPARATOR, regex=False).explode()
    rules = notes[notes != ""].str.replace(r" \([^)]*\):", ":", regex=True).value_counts()
    rows = [[md_inline(str(text)), str(count)] for text, count in rules.items()]
    return "\n\n".join(
        [
            "## Fields the data lacks, filled by rule",
            "The game needs them and the data does not record them; each was filled by the "
            "rule named (decoy_cli/replay/missing.py). Per round and player: the `inferred` "
            "column of `rounds.csv`. `--missing-fields error` fails such rounds instead.",
            first_rows(["field: rule (players left out)", "times"], rows, "rounds.csv"),
        ]
    )


def warnings_section(tables: Tables) -> str:
    """The rounds replayed with implausible data (`--implausible warn`) and their warnings."""
    rounds = tables.rounds[tables.rounds["warnings"] != ""]
    text = [
        "## Implausible data replayed anyway",
        f"{len(rounds)} rounds were replayed although their data is implausible "
        "(`--implausible warn`); their numbers are in every table above. Each round's warnings "
        "are in the `warnings` column of `rounds.csv`.",
    ]
    rows = [
        [md_inline(Path(str(row.file)).name), str(row.round), md_inline(str(row.warnings))]
        for row in rounds.itertuples()
    ]
    text.append(first_rows(["file", "round", "warnings"], rows, "rounds.csv"))
    return "\n\n".join(text)
