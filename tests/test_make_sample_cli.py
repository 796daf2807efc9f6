"""`decoy make-sample`: a synthetic match written without damage models (rounds end by the bomb
or time), byte-identical for the same seed, the shipped sample reproduced, and one error line for
every bad option."""

from __future__ import annotations

from pathlib import Path

import pytest
from differences import json_difference
from typer.testing import CliRunner

from decoy_cli.cli import app
from decoy_cli.esta import read_match

runner = CliRunner()
WIDE = {"COLUMNS": "220"}
BOMB_OR_TIME = {"TargetBombed", "BombDefused", "TargetSaved"}


def _make(out: Path, *extra: str) -> tuple[int, str, str]:
    result = runner.invoke(
        app,
        ["make-sample", "--out", str(out), "--rounds", "2", "--seed", "1", *extra],
        env=WIDE,
    )
    return result.exit_code, result.stdout, result.stderr


def test_sample_without_models(tmp_path: Path) -> None:
    code, stdout, stderr = _make(tmp_path / "a", "--models", "none")
    assert code == 0, stdout + stderr
    path = tmp_path / "a" / "synthetic-dust2-seed1.json.xz"
    assert path.is_file()
    assert "combat is off" in stdout
    assert "synthetic-dust2-seed1 (synthetic, damage models: none)" in stdout
    assert f"wrote {path}" in stdout
    match = read_match(path)
    assert match.match_id == "synthetic-dust2-seed1" and len(match.rounds) == 2
    provenance = match.meta["provenance"]
    assert provenance["synthetic"] is True
    assert provenance["command"] == "decoy make-sample --rounds 2 --seed 1 --models none"
    for r in match.rounds:
        assert r.end_reason in BOMB_OR_TIME
        assert r.end_reason in stdout
        assert len(r.side_indices("T")) == 5 and len(r.side_indices("CT")) == 5

    code, stdout, stderr = _make(tmp_path / "b", "--models", "none")
    assert code == 0, stdout + stderr
    again = tmp_path / "b" / "synthetic-dust2-seed1.json.xz"
    assert again.read_bytes() == path.read_bytes()


def test_the_shipped_sample_is_what_make_sample_writes(tmp_path: Path) -> None:
    """The built-in sample is the project's own output, current with its code, graph and models:
    the command in examples/sample/README.md reproduces it byte for byte (when the simulator,
    the graph or the shipped models change, regenerate it with that command)."""
    shipped = Path(__file__).parents[1] / "examples" / "sample" / "synthetic-dust2-seed0.json.xz"
    args = ["--out", str(tmp_path), "--rounds", "8", "--seed", "0", "--models", "rules"]
    result = runner.invoke(app, ["make-sample", *args], env=WIDE)
    assert result.exit_code == 0, result.output
    built = tmp_path / shipped.name
    assert built.read_bytes() == shipped.read_bytes(), json_difference(built, shipped)


@pytest.mark.parametrize(
    ("args", "expected"),
    [
        (["--rounds", "0"], "error: --rounds must be between 1 and 30, not 0"),
        (["--rounds", "31"], "error: --rounds must be between 1 and 30, not 31"),
        (["--seed", "-1"], "error: --seed must be >= 0, not -1"),
        (["--models", "{tmp}/missing"], "error: {tmp}/missing: no such model folder"),
        (["--models", "shipped"], "error: no shipped damage models in {tmp}"),
    ],
)
def test_bad_options_are_one_error_line(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, args: list[str], expected: str
) -> None:
    monkeypatch.setattr("decoy_cli.damage.SHIPPED_MODELS", tmp_path)
    args = [a.format(tmp=tmp_path) for a in args]
    result = runner.invoke(app, ["make-sample", "--out", str(tmp_path / "out"), *args])
    assert result.exit_code == 1
    assert result.stderr.startswith(expected.format(tmp=tmp_path))
    assert result.stderr.count("\n") == 1 and "Traceback" not in result.output
    assert not (tmp_path / "out").exists()


def test_unwritable_output_is_one_error_line(tmp_path: Path) -> None:
    blocker = tmp_path / "file"
    blocker.write_text("")
    result = runner.invoke(
        app, ["make-sample", "--out", str(blocker), "--rounds", "1", "--models", "none"]
    )
    assert result.exit_code == 1
    assert result.stderr == f"error: cannot write into {blocker}: it is a file, not a folder\n"
    assert result.stderr.count("\n") == 1 and "Traceback" not in result.output
