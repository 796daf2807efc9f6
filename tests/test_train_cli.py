"""`decoy train dip|dog` and `decoy models evaluate` through the CLI, on generated ESTA matches
(tests/esta_fixtures.py); the paper's checkpoints when ../shared/data has them."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import pytest
from esta_fixtures import make_match, shift_ticks, write_match
from typer.testing import CliRunner

from decoy_cli.cli import app
from decoy_cli.damage.model_folder import load_dip, load_dog

DATA = Path(__file__).resolve().parents[1].parent / "shared" / "data"
CHECKPOINTS = DATA / "decoy_checkpoints"

runner = CliRunner()
WIDE = {"COLUMNS": "220"}
ROUNDS = 8
FAST = ["--epochs", "2", "--batch-size", "4", "--split", "round", "--seed", "1"]


def many_rounds() -> dict[str, Any]:
    """The fixture match with its round 2 (both teams' frames, two hits) played ROUNDS times."""
    document = make_match()
    template = document["gameRounds"][1]
    document["gameRounds"] = [
        {**shift_ticks(template, 10_000 * n), "roundNum": n} for n in range(1, 9)
    ]
    return document


@pytest.fixture(scope="module")
def data(tmp_path_factory: pytest.TempPathFactory) -> Path:
    folder = tmp_path_factory.mktemp("train")
    write_match(folder / "match.json.xz", many_rounds())
    return folder


@pytest.fixture(scope="module")
def trained(data: Path, tmp_path_factory: pytest.TempPathFactory) -> Path:
    out = tmp_path_factory.mktemp("model")
    for extra in (["dip"], ["dog", "--min-cell", "1000"]):  # no cell: a NaN mean Wasserstein
        argv = ["train", extra[0], str(data), "--out", str(out), *FAST, *extra[1:]]
        result = runner.invoke(app, argv, env=WIDE)
        assert result.exit_code == 0, result.output
    return out


def test_train_writes_model_folder_and_report(trained: Path) -> None:
    assert sorted(p.name for p in trained.iterdir()) == [
        "dip.json",
        "dip.pt",
        "dog.json",
        "dog.pt",
        "report",
    ]
    assert sorted(p.name for p in (trained / "report").iterdir()) == [
        "dip_curves.png",
        "dip_history.csv",
        "dip_metrics.json",
        "dog_error_histogram.png",
        "dog_generated_vs_real.png",
        "dog_history.csv",
        "dog_hit_group_confusion.png",
        "dog_metrics.json",
        "dog_reconstruction.png",
    ]
    dip, dog = load_dip(trained), load_dog(trained)
    assert 0.0 <= dip.threshold <= 1.0  # a probability, not a logit
    # the test metrics were taken at the threshold the model ships with
    assert dip.metadata["test_metrics"]["threshold"] == dip.threshold
    units = dip.metadata["split"]["units"]
    assert [len(units[n]) for n in ("train", "val", "test")] == [6, 1, 1]
    assert not set(units["train"]) & set(units["test"])
    assert dog.metadata["split"]["units"] == units  # same seed, same rounds
    assert dip.metadata["test_metrics"]["positives"] == 2  # one test round, two hits
    assert dog.metadata["loss_weights"] == {"damage": 1.0, "hit_group": 0.7, "kl": 0.2}
    assert dog.metadata["test_metrics"]["mean_wasserstein_hp"] is None  # strict JSON: no NaN
    assert "NaN" not in (trained / "dog.json").read_text()
    history = (trained / "report" / "dip_history.csv").read_text().splitlines()
    assert history[0] == "epoch,train_loss,val_loss,best" and len(history) == 3


def test_train_prints_the_paper_beside(data: Path, tmp_path: Path) -> None:
    result = runner.invoke(
        app, ["train", "dip", str(data), "--out", str(tmp_path), *FAST], env=WIDE
    )
    assert result.exit_code == 0, result.output
    assert "DIP on the test part" in result.output
    assert "0.951" in result.output  # the paper's ROC AUC
    assert "split by round (seed 1): 1 test, 1 val, 6 train" in result.output


def test_a_dip_on_relative_features_keeps_its_units(data: Path, tmp_path: Path) -> None:
    args = ["train", "dip", str(data), "--out", str(tmp_path), "--units", "relative", *FAST]
    result = runner.invoke(app, args, env=WIDE)
    assert result.exit_code == 0, result.output
    assert load_dip(tmp_path).spec.units == "relative"


def test_evaluate_the_test_part_again(trained: Path, data: Path, tmp_path: Path) -> None:
    """`models evaluate` with the training's split options scores the same test part."""
    out = tmp_path / "evaluation"
    args = ["--subset", "test", "--split", "round", "--seed", "1", "--min-cell", "1"]
    result = runner.invoke(
        app, ["models", "evaluate", str(trained), str(data), "--out", str(out), *args], env=WIDE
    )
    assert result.exit_code == 0, result.output
    metrics = json.loads((out / "metrics.json").read_text())
    trained_dip = load_dip(trained).metadata["test_metrics"]
    assert metrics["dip"]["roc_auc"] == pytest.approx(trained_dip["roc_auc"], nan_ok=True)
    assert metrics["dip"]["threshold"] == pytest.approx(trained_dip["threshold"])
    trained_dog = load_dog(trained).metadata["test_metrics"]
    assert metrics["dog"]["damage_mae_hp"] == pytest.approx(trained_dog["damage_mae_hp"])
    assert len(list(out.glob("*.png"))) == 5


def test_evaluate_with_an_unreadable_file_fails_after_writing(
    trained: Path, data: Path, tmp_path: Path
) -> None:
    """A corrupt file among the data: the metrics of the rest are written, then one error line
    and a non-zero exit, as `decoy evaluate` does."""
    folder = tmp_path / "data"
    folder.mkdir()
    for file in data.iterdir() if data.is_dir() else [data]:
        (folder / file.name).write_bytes(file.read_bytes())
    (folder / "corrupt.json.xz").write_bytes(b"\xfd7zXZ\x00 not xz")
    out = tmp_path / "evaluation"
    result = runner.invoke(
        app, ["models", "evaluate", str(trained), str(folder), "--out", str(out)], env=WIDE
    )
    assert result.exit_code == 1, result.output
    assert result.stderr == (
        "error: 1 input failed and is left out of the metrics (listed above)\n"
    )
    assert "corrupt.json.xz" in result.stdout and (out / "metrics.json").is_file()


@pytest.mark.skipif(
    not (CHECKPOINTS / "dip_best_model.pth").is_file(),
    reason="../shared/data/decoy_checkpoints (the paper's weights) is absent",
)
def test_evaluate_the_paper_models(data: Path, tmp_path: Path) -> None:
    from decoy_cli.modeling.paper_import import import_paper

    paper = import_paper(CHECKPOINTS, tmp_path / "paper").folder
    out = tmp_path / "evaluation"
    result = runner.invoke(
        app,
        ["models", "evaluate", str(paper), str(data), "--out", str(out), "--min-cell", "2"],
        env=WIDE,
    )
    assert result.exit_code == 0, result.output
    metrics = json.loads((out / "metrics.json").read_text())
    assert metrics["dip"]["threshold"] == 0.444
    assert metrics["dip"]["positives"] == 2 * ROUNDS
    assert metrics["dog"]["samples"] == 2 * ROUNDS


@pytest.mark.parametrize(
    ("args", "expected"),
    [
        (["train", "dip", "{missing}"], "error: {missing}: no such file or folder"),
        (["train", "dip", "{data}"], "error: a split by match needs at least 3 matches"),
        (["train", "dip", "{data}", "--epochs", "0"], "error: epochs must be at least 1"),
        (["train", "dog", "{data}", "--kl-weight", "-1"], "error: the KL weight must not"),
        (["train", "dip", "{empty}"], "error: {empty}: no usable samples"),
        (["models", "evaluate", "{missing}", "{data}"], "error: {missing}: no such model"),
        (["models", "evaluate", "{data}", "{data}"], "error: {data}: holds neither dip.json"),
    ],
)
def test_bad_input_is_one_line(args: list[str], expected: str, data: Path, tmp_path: Path) -> None:
    empty = tmp_path / "empty.json.xz"
    document = make_match()
    document["gameRounds"] = [document["gameRounds"][2]]  # world damage only, no frames
    write_match(empty, document)
    names = {"missing": tmp_path / "missing", "data": data, "empty": empty}
    argv = [a.format(**names) for a in args] + ["--out", str(tmp_path / "out")]
    result = runner.invoke(app, argv, env=WIDE)
    assert result.exit_code == 1, result.output
    assert result.stderr.startswith(expected.format(**names))
    assert result.stderr.count("\n") == 1 and "Traceback" not in result.output


@pytest.mark.parametrize(
    "command",
    [
        ["train", "dip"],
        ["train", "dog"],
        ["models", "evaluate", "rules"],
        ["models", "calibrate", "m"],
    ],
)
@pytest.mark.parametrize(("option", "value"), [("--mode", "movie"), ("--split", "player")])
def test_the_sample_options_are_one_group_with_choices(
    command: list[str], option: str, value: str, data: Path
) -> None:
    """Every command that reads and splits samples takes the same group of options, with
    their choices listed in its help and a bad choice refused in one usage line."""
    argv = [*command, str(data), option, value]
    result = runner.invoke(app, argv, env=WIDE)
    assert result.exit_code == 2 and result.stderr.count("\n") == 1, result.output
    assert f"Invalid value for '{option}'" in result.stderr
    shown = runner.invoke(app, [*command[:2], "--help"], env=WIDE).output
    for text in ("--mode", "auto|frames|events", "--split", "match|round", "--val-fraction"):
        assert text in shown


@pytest.mark.parametrize(
    ("command", "option", "value", "choices"),
    [
        (["train", "dip"], "--balance", "x", "all|eval|none"),
        (["models", "evaluate", "rules"], "--subset", "some", "all|train|val|test"),
        (["models", "calibrate", "models"], "--method", "isotonic", "platt|temperature|none"),
        (["models", "calibrate", "models"], "--decision", "coin", "threshold|bernoulli"),
    ],
)
def test_a_choice_of_a_damage_command_is_listed_and_a_bad_one_refused(
    command: list[str], option: str, value: str, choices: str, data: Path
) -> None:
    """--balance, --subset, --method and --decision take one of a listed few: a bad value is
    one usage line before anything is read, and the help lists them."""
    result = runner.invoke(app, [*command, str(data), option, value], env=WIDE)
    assert result.exit_code == 2 and result.stderr.count("\n") == 1, result.output
    assert f"Invalid value for '{option}'" in result.stderr
    assert choices in runner.invoke(app, [*command[:2], "--help"], env=WIDE).output


def test_a_corrupt_file_is_reported_and_training_goes_on(data: Path, tmp_path: Path) -> None:
    """The one round loop: a corrupt file in the training folder is a recorded failure, printed
    and kept in the model's metadata, and the model is trained on the rest."""
    folder = tmp_path / "data"
    folder.mkdir()
    (folder / "match.json.xz").write_bytes((data / "match.json.xz").read_bytes())
    (folder / "corrupt.json.xz").write_bytes(b"not an xz stream")
    out = tmp_path / "model"
    result = runner.invoke(app, ["train", "dip", str(folder), "--out", str(out), *FAST], env=WIDE)
    assert result.exit_code == 0, result.output
    assert "left out 1 failed input:" in result.output
    assert "corrupt.json.xz (unreadable file):" in result.output
    assert "split by round (seed 1): 1 test, 1 val, 6 train" in result.output
    stats = load_dip(out).metadata["sample_stats"]
    assert stats["files"] == 2 and stats["file_errors"] == 1
    assert [f["kind"] for f in stats["failures"]] == ["unreadable file"]
    assert stats["failures"][0]["file"].endswith("corrupt.json.xz")


def test_only_corrupt_files_is_one_error_line(tmp_path: Path) -> None:
    folder = tmp_path / "data"
    folder.mkdir()
    for name in ("a.json.xz", "b.json.xz"):
        (folder / name).write_bytes(b"not an xz stream")
    result = runner.invoke(
        app, ["train", "dog", str(folder), "--out", str(tmp_path / "out"), *FAST], env=WIDE
    )
    assert result.exit_code == 1, result.output
    assert result.stderr.startswith(f"error: {folder}: no usable samples (2 files")
    assert "2 inputs failed" in result.stderr
    assert result.stderr.count("\n") == 1 and "Traceback" not in result.output
    assert not (tmp_path / "out").exists()
