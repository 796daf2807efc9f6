"""Hostile JSON in the files decoy reads besides match files (issue 51): a model folder's
`dip.json`, `dog.json`, `rules.json` and calibration, through `decoy models evaluate` and
`--models DIR`; and the one loader they go through (decoy_cli/reading.py). Deep nesting, numbers
that are not finite or overflow, and any other damage are one `error:` line naming the file,
never the bug line (exit 2)."""

from __future__ import annotations

import json
import math
import shutil
from pathlib import Path

import pytest
from esta_fixtures import make_match, write_match
from typer.testing import CliRunner

from decoy_cli.cli import app
from decoy_cli.damage.bullet_counts import MAX_BULLETS, BulletCounts
from decoy_cli.errors import ModelError
from decoy_cli.reading import MAX_JSON_DEPTH, load_json

ROOT = Path(__file__).resolve().parents[1]
runner = CliRunner()
DEEP = "[" * 100_000 + "]" * 100_000
"""Nesting far deeper than Python's recursion limit."""


def one_error(result) -> str:
    """The `error:` line of a command that failed on bad input (exit 1, no bug line)."""
    assert result.exit_code == 1, result.output
    assert "Traceback" not in result.output and "internal error" not in result.output
    assert result.stderr.count("\n") == 1 and result.stderr.startswith("error: "), result.stderr
    return result.stderr.strip()


def model_folder(tmp_path: Path) -> Path:
    """A copy of the shipped models' DIP, calibration and rules (a rules-grounded folder)."""
    folder = tmp_path / "models"
    folder.mkdir()
    for name in ("dip.pt", "dip.json", "dip_calibration.json", "rules.json"):
        shutil.copy(ROOT / "models" / name, folder / name)
    return folder


def with_field(path: Path, key: str, raw: str) -> None:
    """Add `key` holding the raw JSON text `raw` to the object in `path`."""
    text = path.read_text().rstrip()
    assert text.endswith("}")
    path.write_text(f"{text[:-1]}, {json.dumps(key)}: {raw}}}")


@pytest.fixture(scope="module")
def data(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return write_match(tmp_path_factory.mktemp("data") / "m.json", make_match())


@pytest.mark.parametrize("name", ["dip.json", "rules.json", "dip_calibration.json"])
def test_deep_json_in_a_model_folder_is_one_error_line(
    tmp_path: Path, data: Path, name: str
) -> None:
    folder = model_folder(tmp_path)
    with_field(folder / name, "deep", DEEP)
    line = one_error(
        runner.invoke(app, ["models", "evaluate", str(folder), str(data), "--out", str(tmp_path)])
    )
    assert f"{folder / name}: JSON nested deeper than {MAX_JSON_DEPTH} levels" in line
    replay = runner.invoke(
        app, ["replay", f"{data}:1", "--models", str(folder), "--out", str(tmp_path / "r")]
    )
    assert f"{folder / name}: JSON nested deeper" in one_error(replay)


def test_the_loader_refuses_deep_nesting_by_its_limit(tmp_path: Path) -> None:
    path = tmp_path / "x.json"
    path.write_text("[" * MAX_JSON_DEPTH + "]" * MAX_JSON_DEPTH)
    assert load_json(path) == _nested(MAX_JSON_DEPTH)
    path.write_text("[" * (MAX_JSON_DEPTH + 1) + "]" * (MAX_JSON_DEPTH + 1))
    with pytest.raises(ModelError, match="nested deeper than"):
        load_json(path, ModelError)


def _nested(levels: int) -> list:
    value: list = []
    for _ in range(levels - 1):
        value = [value]
    return value


@pytest.mark.parametrize(
    ("raw", "said"),
    [
        ("Infinity", "bullets.counts.AK-47[1]: Infinity is not a finite number"),
        ("-Infinity", "bullets.counts.AK-47[1]: -Infinity is not a finite number"),
        ("NaN", "bullets.counts.AK-47[1]: NaN is not a finite number"),
        ("1e999", "bullets.counts.AK-47[1]: 1e999 is beyond the range of a float"),
        ("-3", "bullets 'AK-47': counts must be finite and not negative"),
    ],
)
def test_a_bullet_count_that_is_no_count_is_refused_by_name(
    tmp_path: Path, data: Path, raw: str, said: str
) -> None:
    folder = model_folder(tmp_path)
    rules = folder / "rules.json"
    document = json.loads(rules.read_text())
    document["bullets"]["counts"]["AK-47"][1] = "COUNT"
    rules.write_text(json.dumps(document).replace('"COUNT"', raw))
    line = one_error(
        runner.invoke(app, ["models", "evaluate", str(folder), str(data), "--out", str(tmp_path)])
    )
    assert line.startswith(f"error: {rules}: ") and said in line, line


def test_bullet_counts_check_names_a_count_that_is_not_finite() -> None:
    counts = BulletCounts({"AK-47": [1.0] * MAX_BULLETS}, {"AK-47": [0.0] * MAX_BULLETS})
    counts.check("bullets")
    for bad in (math.inf, math.nan, -1.0):
        counts.counts["AK-47"][3] = bad
        with pytest.raises(ValueError, match="bullets_hurt 'AK-47': counts must be finite"):
            counts.check("bullets_hurt")
