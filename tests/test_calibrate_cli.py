"""`decoy models calibrate`: the shipped DIP calibrated on the real events' validation rounds."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

from decoy_cli.cli import app
from decoy_cli.damage.model_folder import load_dip

runner = CliRunner()
WIDE = {"COLUMNS": "200"}
ROOT = Path(__file__).resolve().parents[1]
EVENTS = ROOT.parent / "shared" / "data" / "esta_dust2_events"


@pytest.mark.skipif(not EVENTS.is_dir(), reason="needs ../shared/data/esta_dust2_events")
def test_calibrating_the_shipped_dip(tmp_path: Path) -> None:
    folder = tmp_path / "models"
    shutil.copytree(ROOT / "models", folder)
    split = ["--split", "round"]
    result = runner.invoke(app, ["models", "calibrate", str(folder), str(EVENTS), *split], env=WIDE)
    assert result.exit_code == 0, result.output
    assert "DIP calibration (platt)" in result.output
    fight = json.loads((ROOT / "models" / "dip_calibration.json").read_text())["threshold"]
    assert f"replaces the folder's none calibration (threshold {fight:.3f})" in result.output
    dip = load_dip(folder)
    assert dip.calibration is not None and dip.calibration.kind == "platt"
    # the fight's operating point carries over onto the calibrated scale: the same pairs hit
    assert dip.calibration.threshold == pytest.approx(dip.calibration.apply(np.array([fight]))[0])
    out = tmp_path / "evaluation"
    args = ["--subset", "test", "--no-balance", *split, "--out", str(out)]
    evaluated = runner.invoke(
        app, ["models", "evaluate", str(folder), str(EVENTS), *args], env=WIDE
    )
    assert evaluated.exit_code == 0, evaluated.output
    metrics = json.loads((out / "metrics.json").read_text())["dip"]
    # fitted on the validation rounds, checked on the test rounds it never saw
    assert metrics["ece_calibrated"] < metrics["ece"]
    assert metrics["brier_calibrated"] < metrics["brier"]
    assert "expected calibration error, calibrated" in evaluated.output
    assert 0.0 < metrics["ece_floor"] < metrics["ece"]
    assert "ECE floor" in result.output


def test_a_folder_without_dip_is_one_error_line(tmp_path: Path) -> None:
    result = runner.invoke(app, ["models", "calibrate", str(tmp_path), str(tmp_path)], env=WIDE)
    assert result.exit_code == 1
    assert "error: " in result.output and "no dip.json" in result.output
    assert "Traceback" not in result.output
