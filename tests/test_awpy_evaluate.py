"""`decoy evaluate` on one demo's tables in both awpy layouts: the same tables, with the fight's
random numbers too (a CS2 round is seeded by its place in its demo, not by its file's bytes)."""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

from typer.testing import CliRunner

from decoy_cli.cli import app
from decoy_cli.esta import read_match
from decoy_cli.esta.awpy.writer import write_awpy2_zip, write_awpy3_folder
from decoy_cli.synth.sample import SAMPLE_DIR


def test_both_layouts_of_one_demo_evaluate_to_the_same_tables(tmp_path: Path) -> None:
    sample = read_match(sorted(SAMPLE_DIR.glob("*.json*"))[0])
    match = replace(sample, rounds=sample.rounds[:2])
    sources = [
        write_awpy2_zip(match, tmp_path / "m.zip"),
        write_awpy3_folder(match, tmp_path / "m"),
    ]
    tables = []
    # the zip in a worker process, the folder in this one: two processes, so a fight seeded by
    # anything a process draws for itself (str hashes) cannot give both the same tables, and
    # one pool to start instead of two
    for k, (source, workers) in enumerate(zip(sources, ("1", "0"), strict=True)):
        out = tmp_path / f"run{k}"
        args = [
            "evaluate",
            str(source),
            "--seed",
            "5",
            "--workers",
            workers,
            "--no-view",
            "--no-figures",
        ]
        result = CliRunner().invoke(app, [*args, "--out", str(out)])
        assert result.exit_code == 0, result.output
        tables.append({p.name: p.read_text() for p in sorted((out / "tables").glob("*.csv"))})
    assert tables[0].keys() == tables[1].keys() and "combat.csv" in tables[0]
    assert tables[0] == tables[1]
