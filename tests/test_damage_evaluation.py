"""Metrics and figures of the damage models (decoy_cli/modeling/scores.py, network_evaluation.py,
evaluation_figures.py): numbers checked by hand, the network runners on untrained networks
(shapes, ranges, determinism under a seed)."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
import torch
from scipy.stats import wasserstein_distance
from test_damage_training import planted

from decoy_cli.damage.features import FeatureSpec
from decoy_cli.damage.model_folder import LoadedDip, LoadedDog
from decoy_cli.damage.networks import DipNet, DogNet
from decoy_cli.modeling.evaluation_figures import write_dip_figures, write_dog_figures
from decoy_cli.modeling.network_evaluation import dog_generate, evaluate_dip, evaluate_dog
from decoy_cli.modeling.scores import (
    Cell,
    average_precision,
    best_f1_threshold,
    classification_metrics,
    confusion_matrix,
    precision_recall_curve,
    regression_metrics,
    roc_auc,
    roc_curve,
    sampling_floor,
    tv_floor,
    wasserstein_cells,
)

LABELS = np.array([1, 0, 1, 1, 0], dtype=bool)
SCORES = np.array([0.9, 0.8, 0.7, 0.4, 0.2])


def test_roc_auc_by_hand() -> None:
    """Positive-negative pairs ranked right: 0.9 > 0.8, 0.9 > 0.2, 0.7 > 0.2, 0.4 > 0.2; wrong:
    0.7 < 0.8, 0.4 < 0.8. AUC = 4 / 6."""
    assert roc_auc(LABELS, SCORES) == pytest.approx(4 / 6)
    assert roc_auc(LABELS, np.full(5, 0.3)) == pytest.approx(0.5)  # ties count half
    assert roc_auc(LABELS, -SCORES) == pytest.approx(2 / 6)
    assert math.isnan(roc_auc(np.ones(3, bool), np.array([0.1, 0.2, 0.3])))


def test_average_precision_by_hand() -> None:
    """Descending: hit (P 1, R 1/3), miss, hit (P 2/3, R 2/3), hit (P 3/4, R 1), miss:
    AP = 1/3 * 1 + 1/3 * 2/3 + 1/3 * 3/4."""
    assert average_precision(LABELS, SCORES) == pytest.approx((1 + 2 / 3 + 3 / 4) / 3)
    assert average_precision(LABELS, np.full(5, 0.3)) == pytest.approx(0.6)  # prevalence
    assert math.isnan(average_precision(np.zeros(3, bool), np.array([0.1, 0.2, 0.3])))


def test_metrics_at_a_threshold_by_hand() -> None:
    """At 0.5: predicted 1, 1, 1, 0, 0 -> TP 2, FP 1, FN 1, TN 1."""
    metrics = classification_metrics(LABELS, SCORES, 0.5)
    assert metrics["accuracy"] == pytest.approx(0.6)
    assert metrics["precision"] == pytest.approx(2 / 3)
    assert metrics["recall"] == pytest.approx(2 / 3)
    assert metrics["f1"] == pytest.approx(2 / 3)
    assert (metrics["positives"], metrics["negatives"]) == (3, 2)
    assert classification_metrics(LABELS, SCORES, 0.4)["recall"] == 1.0  # at or above


def test_best_f1_threshold_by_hand() -> None:
    """F1 at 0.9, 0.8, 0.7, 0.4, 0.2: 2/4, 2/5, 4/6, 6/7, 6/8: the best is 0.4."""
    assert best_f1_threshold(LABELS, SCORES) == pytest.approx(0.4)
    with pytest.raises(ValueError, match="positive"):
        best_f1_threshold(np.zeros(3, bool), np.array([0.1, 0.2, 0.3]))


def test_curves() -> None:
    fpr, tpr = roc_curve(LABELS, SCORES)
    np.testing.assert_allclose(fpr, [0, 0, 0.5, 0.5, 0.5, 1])
    np.testing.assert_allclose(tpr, [0, 1 / 3, 1 / 3, 2 / 3, 1, 1])
    assert np.trapezoid(tpr, fpr) == pytest.approx(roc_auc(LABELS, SCORES))
    recall, precision = precision_recall_curve(LABELS, SCORES)
    np.testing.assert_allclose(recall, [1 / 3, 1 / 3, 2 / 3, 1, 1])
    np.testing.assert_allclose(precision, [1, 1 / 2, 2 / 3, 3 / 4, 3 / 5])


def test_bad_metric_input() -> None:
    with pytest.raises(ValueError, match="labels for"):
        roc_auc(LABELS, SCORES[:3])
    with pytest.raises(ValueError, match="finite"):
        roc_auc(LABELS, np.array([0.1, np.nan, 0.3, 0.4, 0.5]))


def test_regression_and_confusion_by_hand() -> None:
    """Real 0, 10, 20, predicted 0, 10, 30: MAE 10/3; R² = 1 - 100 / 200."""
    metrics = regression_metrics(np.array([0.0, 10, 20]), np.array([0.0, 10, 30]))
    assert metrics["mae"] == pytest.approx(10 / 3)
    assert metrics["r2"] == pytest.approx(0.5)
    assert math.isnan(regression_metrics(np.ones(3), np.ones(3))["r2"])
    matrix = confusion_matrix(np.array([0, 0, 2, 5]), np.array([0, 1, 2, 5]), 6)
    assert matrix.sum() == 4 and matrix[0, 0] == 1 and matrix[0, 1] == 1 and matrix[5, 5] == 1


def test_wasserstein_cells() -> None:
    rng = np.random.default_rng(0)
    weapon = np.array(["AK-47"] * 30 + ["AWP"] * 12 + ["P250"] * 3, dtype=object)
    group = np.array([2] * 20 + [0] * 10 + [2] * 12 + [0] * 3)
    damage = rng.uniform(10, 100, len(weapon))
    generated_damage = rng.uniform(10, 100, 200)
    generated_weapon = np.array(["AK-47"] * 100 + ["AWP"] * 100, dtype=object)
    generated_group = np.array([2] * 60 + [0] * 40 + [2] * 95 + [0] * 5)
    cells = wasserstein_cells(
        weapon, group, damage, generated_weapon, generated_group, generated_damage, min_cell=10
    )
    assert [(c.weapon, c.part, c.real, c.generated) for c in cells] == [
        ("AK-47", "Chest", 20, 60),
        ("AWP", "Chest", 12, 95),
        ("AK-47", "Head", 10, 40),
    ]
    expected = wasserstein_distance(damage[:20], generated_damage[:60])
    assert cells[0].wasserstein_hp == pytest.approx(expected)


def test_sampling_floor_is_what_draws_of_the_model_itself_score() -> None:
    rng = np.random.default_rng(1)
    # 85 AK-47 chest samples whose model draws are normal(30, 10), and 5 AWP chest samples the
    # model always gives 77 HP; 400 draws of each
    weapon = np.array(["AK-47"] * 85 + ["AWP"] * 5, dtype=object)
    group = np.full((400, 90), 2)
    damage = np.concatenate([rng.normal(30, 10, (400, 85)), np.full((400, 5), 77.0)], axis=1)
    (few,) = sampling_floor(
        [Cell("AK-47", "Chest", 5, 0, 0.0)], weapon[80:], group[:, 80:], damage[:, 80:]
    )
    many, constant = sampling_floor(
        [Cell("AK-47", "Chest", 85, 0, 0.0), Cell("AWP", "Chest", 5, 0, 0.0)], weapon, group, damage
    )
    assert constant == 0.0  # a model that always does 77 HP matches any sample of itself
    assert many < few / 2  # more samples, less room for chance
    by_hand = np.mean(
        [wasserstein_distance(rng.normal(30, 10, 5), rng.normal(30, 10, 2000)) for _ in range(400)]
    )
    assert few == pytest.approx(by_hand, rel=0.15)


def test_tv_floor_by_hand() -> None:
    # one sample drawn 50/50 between two groups: its share is always 0 or 1, total variation 0.5
    halves = np.array([[0], [2]] * 50)
    assert tv_floor(halves) == (pytest.approx(0.5), 1.0)
    assert tv_floor(np.full((10, 7), 3)) == (0.0, 0.0)  # always the same group
    rng = np.random.default_rng(0)
    mean, above = tv_floor(rng.choice([0, 2, 3], size=(200, 1000), p=[0.4, 0.4, 0.2]))
    assert mean < 0.03 and above == 0.0


SPEC = FeatureSpec()


def untrained_dip() -> LoadedDip:
    torch.manual_seed(0)
    return LoadedDip(DipNet().eval(), SPEC, 0.5)


def untrained_dog() -> LoadedDog:
    torch.manual_seed(0)
    return LoadedDog(DogNet().eval(), SPEC)


def test_evaluate_dip_shapes() -> None:
    samples = planted(300, seed=1)
    result = evaluate_dip(untrained_dip(), samples)
    assert result.probabilities.shape == (300,)
    assert ((result.probabilities > 0) & (result.probabilities < 1)).all()
    assert result.metrics["threshold"] == 0.5
    # the metrics are those of the returned probabilities at the threshold
    predicted = result.probabilities >= 0.5
    assert result.metrics["accuracy"] == pytest.approx(np.mean(predicted == samples.hit))
    hits = int(samples.hit.sum())
    assert result.metrics["recall"] == pytest.approx(np.sum(predicted & samples.hit) / hits)
    assert evaluate_dip(untrained_dip(), samples, threshold=0.2).metrics["threshold"] == 0.2


def test_evaluate_dog_is_seeded_and_in_range() -> None:
    samples = planted(400, seed=2)
    one = evaluate_dog(untrained_dog(), samples, seed=3, draws=4, min_cell=2)
    two = evaluate_dog(untrained_dog(), samples, seed=3, draws=4, min_cell=2)
    other = evaluate_dog(untrained_dog(), samples, seed=4, draws=4, min_cell=2)
    hits = int(samples.hit.sum())
    assert one.metrics["samples"] == hits
    assert one.generated_damage.shape == (4 * hits,)
    assert ((one.generated_damage >= 1) & (one.generated_damage <= 100)).all()
    assert np.array_equal(one.generated_damage, np.rint(one.generated_damage))
    np.testing.assert_array_equal(one.generated_damage, two.generated_damage)
    np.testing.assert_array_equal(one.reconstructed_damage, two.reconstructed_damage)
    assert not np.array_equal(one.reconstructed_damage, other.reconstructed_damage)
    with pytest.raises(ValueError, match="draws"):
        dog_generate(untrained_dog(), samples, 0, draws=0)
    with pytest.raises(ValueError, match="no damaging samples"):
        evaluate_dog(untrained_dog(), samples.take(~samples.hit))


def test_figures_are_written(tmp_path: Path) -> None:
    samples = planted(300, seed=5)
    dip_paths = write_dip_figures(evaluate_dip(untrained_dip(), samples), tmp_path)
    dog_paths = write_dog_figures(
        evaluate_dog(untrained_dog(), samples, draws=2, min_cell=2), tmp_path
    )
    names = sorted(p.name for p in dip_paths + dog_paths)
    assert names == [
        "dip_curves.png",
        "dog_error_histogram.png",
        "dog_generated_vs_real.png",
        "dog_hit_group_confusion.png",
        "dog_reconstruction.png",
    ]
    for path in dip_paths + dog_paths:
        assert path.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
