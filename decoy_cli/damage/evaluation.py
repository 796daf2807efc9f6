"""How good a DIP and a DOG are on samples: the paper's metrics and figures.

DIP (a classifier of "does the attacker damage the victim in this step"): accuracy, precision,
recall and F1 at the decision threshold, ROC AUC and average precision over all thresholds.
The threshold of a trained DIP is chosen on the validation split by `best_f1_threshold`.

DOG (a conditional VAE of the damage and hit group of a damaging pair):

* reconstruction mode, as the paper reports it: the true damage and hit group are encoded, z is
  drawn from the posterior and decoded; damage MAE (HP) and R², and hit-group accuracy (which
  is high because the true hit group is an input);
* generative mode, as the simulator uses DOG: z ~ N(0, I), `draws` samples per test condition,
  damage rounded and kept in [1, 100] HP, hit group the most likely one (the simulator's rule,
  decoy_cli/damage/combat.py); hit-group accuracy, and the Wasserstein distance
  (scipy.stats.wasserstein_distance) between generated and real damage per (weapon, hit group)
  cell. A cell counts when it holds at least `min_cell` real samples (default 10) and as many
  generated ones; the real cell is the samples with that weapon and real hit group, the
  generated cell the draws with that weapon and generated hit group. Their mean is the paper's
  "mean Wasserstein".

Numbers are plain numpy and scipy (no scikit-learn). torch, matplotlib and scipy.stats (0.7 s
to import, and the CLI imports this module for its constants) are imported by the functions
that use them.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from decoy_cli.damage.features import HIT_GROUPS
from decoy_cli.damage.sample_set import MAX_DAMAGE_HP, Samples
from decoy_cli.figures import save_figure

if TYPE_CHECKING:
    from decoy_cli.damage.model_folder import LoadedDip, LoadedDog

PAPER_DIP = {
    "accuracy": 0.908,
    "f1": 0.913,
    "roc_auc": 0.951,
    "average_precision": 0.927,
    "threshold": 0.444,
}
"""The paper's DIP test metrics."""

PAPER_DOG = {
    "damage_mae_hp": 13.97,
    "damage_r2": 0.687,
    "hit_group_accuracy": 0.966,
    "mean_wasserstein_hp": 9.87,
}
"""The paper's DOG test metrics (MAE, R² and hit-group accuracy in reconstruction mode)."""

MIN_CELL = 10
"""Fewest real samples a (weapon, hit group) cell needs to enter the mean Wasserstein."""

DRAWS = 10
"""Generated samples per test condition in generative mode."""

_BATCH = 65_536


# ---- numbers ----------------------------------------------------------------------------------


def _check(labels: np.ndarray, scores: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    labels = np.asarray(labels, dtype=bool).ravel()
    scores = np.asarray(scores, dtype=np.float64).ravel()
    if labels.shape != scores.shape:
        raise ValueError(f"{len(labels)} labels for {len(scores)} scores")
    if not np.all(np.isfinite(scores)):
        raise ValueError("scores must be finite")
    return labels, scores


def roc_auc(labels: np.ndarray, scores: np.ndarray) -> float:
    """Area under the ROC curve (the Mann-Whitney U statistic, ties counted half); NaN when
    only one class is present."""
    from scipy.stats import rankdata

    labels, scores = _check(labels, scores)
    positives = int(labels.sum())
    negatives = len(labels) - positives
    if positives == 0 or negatives == 0:
        return math.nan
    ranks = rankdata(scores)
    return float((ranks[labels].sum() - positives * (positives + 1) / 2) / (positives * negatives))


def _ranked(labels: np.ndarray, scores: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """True and false positives when predicting positive at or above each distinct score
    (descending), and those scores."""
    order = np.argsort(-scores, kind="stable")
    sorted_scores, sorted_labels = scores[order], labels[order]
    last = np.r_[np.flatnonzero(np.diff(sorted_scores)), len(scores) - 1]
    true_pos = np.cumsum(sorted_labels)[last]
    false_pos = last + 1 - true_pos
    return true_pos, false_pos, sorted_scores[last]


def average_precision(labels: np.ndarray, scores: np.ndarray) -> float:
    """Average precision, sum over thresholds of (recall step) x precision; NaN without
    positives."""
    labels, scores = _check(labels, scores)
    positives = int(labels.sum())
    if positives == 0:
        return math.nan
    true_pos, false_pos, _ = _ranked(labels, scores)
    precision = true_pos / (true_pos + false_pos)
    recall = true_pos / positives
    return float(np.sum(np.diff(recall, prepend=0.0) * precision))


def roc_curve(labels: np.ndarray, scores: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """False and true positive rates from (0, 0) to (1, 1)."""
    labels, scores = _check(labels, scores)
    true_pos, false_pos, _ = _ranked(labels, scores)
    positives, negatives = max(int(labels.sum()), 1), max(int((~labels).sum()), 1)
    return np.r_[0.0, false_pos / negatives], np.r_[0.0, true_pos / positives]


def precision_recall_curve(labels: np.ndarray, scores: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Recall and precision at each distinct threshold, from the highest threshold down."""
    labels, scores = _check(labels, scores)
    true_pos, false_pos, _ = _ranked(labels, scores)
    return true_pos / max(int(labels.sum()), 1), true_pos / (true_pos + false_pos)


def best_f1_threshold(labels: np.ndarray, scores: np.ndarray) -> float:
    """The score threshold (predict positive at or above it) with the highest F1; the highest
    such threshold on a tie. Used on the validation split, never on test."""
    labels, scores = _check(labels, scores)
    if not labels.any():
        raise ValueError("choosing a threshold needs at least one positive")
    true_pos, false_pos, thresholds = _ranked(labels, scores)
    f1 = 2 * true_pos / (true_pos + false_pos + int(labels.sum()))
    return float(thresholds[int(np.argmax(f1))])


def classification_metrics(
    labels: np.ndarray, scores: np.ndarray, threshold: float
) -> dict[str, float]:
    """Accuracy, precision, recall and F1 at `threshold` (positive at or above it), ROC AUC,
    average precision, the threshold and the class counts."""
    labels, scores = _check(labels, scores)
    predicted = scores >= threshold
    tp = int(np.sum(predicted & labels))
    fp = int(np.sum(predicted & ~labels))
    fn = int(np.sum(~predicted & labels))
    precision = tp / (tp + fp) if tp + fp else math.nan
    recall = tp / (tp + fn) if tp + fn else math.nan
    f1 = 2 * tp / (2 * tp + fp + fn) if tp + fp + fn else math.nan
    return {
        "accuracy": float(np.mean(predicted == labels)) if len(labels) else math.nan,
        "precision": precision,
        "recall": recall,
        "f1": f1,
        "roc_auc": roc_auc(labels, scores),
        "average_precision": average_precision(labels, scores),
        "threshold": float(threshold),
        "positives": int(labels.sum()),
        "negatives": int((~labels).sum()),
    }


def regression_metrics(real: np.ndarray, predicted: np.ndarray) -> dict[str, float]:
    """Mean absolute error and R² (1 - residual / total sum of squares; NaN for constant real
    values)."""
    real = np.asarray(real, dtype=np.float64)
    predicted = np.asarray(predicted, dtype=np.float64)
    if real.shape != predicted.shape or real.size == 0:
        raise ValueError("regression metrics need two non-empty arrays of one shape")
    residual = float(np.sum((real - predicted) ** 2))
    total = float(np.sum((real - real.mean()) ** 2))
    return {
        "mae": float(np.mean(np.abs(real - predicted))),
        "r2": 1.0 - residual / total if total > 0 else math.nan,
    }


def confusion_matrix(real: np.ndarray, predicted: np.ndarray, classes: int) -> np.ndarray:
    """(classes, classes) counts, rows the real class, columns the predicted one."""
    matrix = np.zeros((classes, classes), dtype=np.int64)
    np.add.at(matrix, (np.asarray(real, int), np.asarray(predicted, int)), 1)
    return matrix


@dataclass(frozen=True)
class Cell:
    """One (weapon, hit group) cell: sample counts and the Wasserstein distance in HP."""

    weapon: str
    hit_group: str
    real: int
    generated: int
    wasserstein_hp: float


def wasserstein_cells(
    real_weapon: np.ndarray,
    real_group: np.ndarray,
    real_damage: np.ndarray,
    generated_weapon: np.ndarray,
    generated_group: np.ndarray,
    generated_damage: np.ndarray,
    min_cell: int = MIN_CELL,
) -> list[Cell]:
    """The cells with at least `min_cell` real and generated samples, most real samples first."""
    from scipy.stats import wasserstein_distance

    cells = []
    for weapon in np.unique(real_weapon):
        for code, name in enumerate(HIT_GROUPS):
            real = real_damage[(real_weapon == weapon) & (real_group == code)]
            generated = generated_damage[(generated_weapon == weapon) & (generated_group == code)]
            if len(real) >= min_cell and len(generated) >= min_cell:
                distance = float(wasserstein_distance(real, generated))
                cells.append(Cell(str(weapon), name, len(real), len(generated), distance))
    return sorted(cells, key=lambda c: (-c.real, c.weapon, c.hit_group))


# ---- running the networks ---------------------------------------------------------------------


def dip_probabilities(dip: LoadedDip, samples: Samples) -> np.ndarray:
    """(K,) DIP's probability of damage for every sample (eval mode, batched)."""
    import torch

    from decoy_cli.damage.networks import tensors

    features = samples.features(dip.spec)
    dip.net.eval()
    out = np.zeros(len(samples), dtype=np.float64)
    with torch.inference_mode():
        for start in range(0, len(samples), _BATCH):
            part = features.take(slice(start, start + _BATCH))
            logits = dip.net(*tensors(part))
            out[start : start + len(part)] = torch.sigmoid(logits).numpy()
    return out


@dataclass(frozen=True)
class DipEvaluation:
    """DIP's metrics on samples, with the labels and probabilities behind them."""

    metrics: dict[str, float]
    labels: np.ndarray
    probabilities: np.ndarray


def evaluate_dip(dip: LoadedDip, samples: Samples, threshold: float | None = None) -> DipEvaluation:
    """DIP's metrics on the samples at `threshold` (default: the model's own)."""
    if len(samples) == 0:
        raise ValueError("no samples to evaluate DIP on")
    probabilities = dip_probabilities(dip, samples)
    chosen = dip.threshold if threshold is None else threshold
    return DipEvaluation(
        classification_metrics(samples.hit, probabilities, chosen),
        samples.hit.copy(),
        probabilities,
    )


@dataclass(frozen=True)
class DogEvaluation:
    """DOG's metrics on positive samples and the values behind them (damage in HP)."""

    metrics: dict[str, Any]
    real_damage: np.ndarray
    real_group: np.ndarray
    weapon: np.ndarray
    reconstructed_damage: np.ndarray
    reconstructed_group: np.ndarray
    generated_damage: np.ndarray  # (draws * K,)
    generated_group: np.ndarray
    generated_weapon: np.ndarray
    cells: list[Cell]


def dog_reconstruct(dog: LoadedDog, samples: Samples, seed: int) -> tuple[np.ndarray, np.ndarray]:
    """Reconstruction mode: (damage HP (K,), hit-group code (K,)) decoded from z drawn from the
    posterior of each sample's true damage and hit group (eval mode, seeded)."""
    import torch

    from decoy_cli.damage.networks import tensors

    features = samples.features(dog.spec)
    generator = torch.Generator().manual_seed(seed)
    damage = np.zeros(len(samples))
    group = np.zeros(len(samples), dtype=np.int64)
    dog.net.eval()
    with torch.inference_mode():
        for start in range(0, len(samples), _BATCH):
            rows = slice(start, start + _BATCH)
            part = features.take(rows)
            target = torch.from_numpy(samples.damage[rows].astype(np.float32) / 100.0)
            codes = torch.from_numpy(samples.hit_group[rows].astype(np.int64))
            onehot = torch.nn.functional.one_hot(codes, len(HIT_GROUPS)).float()
            out = dog.net(target[:, None], onehot, *tensors(part), generator=generator)
            damage[rows] = 100.0 * out.damage.squeeze(1).numpy()
            group[rows] = out.hit_logits.argmax(1).numpy()
    return damage, group


def dog_generate(
    dog: LoadedDog, samples: Samples, seed: int, draws: int = DRAWS
) -> tuple[np.ndarray, np.ndarray]:
    """Generative mode: `draws` samples per condition, as (draws, K) damage in HP (rounded, in
    [1, 100]) and hit-group codes (the most likely group), z ~ N(0, I) from a seeded generator."""
    import torch

    from decoy_cli.damage.networks import tensors

    if draws < 1:
        raise ValueError(f"draws must be at least 1, got {draws}")
    features = samples.features(dog.spec)
    generator = torch.Generator().manual_seed(seed)
    damage = np.zeros((draws, len(samples)))
    group = np.zeros((draws, len(samples)), dtype=np.int64)
    dog.net.eval()
    with torch.inference_mode():
        for d in range(draws):
            for start in range(0, len(samples), _BATCH):
                rows = slice(start, start + _BATCH)
                hp, logits = dog.net.generate(*tensors(features.take(rows)), generator=generator)
                damage[d, rows] = np.clip(np.rint(hp.numpy()), 1, MAX_DAMAGE_HP)
                group[d, rows] = logits.argmax(1).numpy()
    return damage, group


def evaluate_dog(
    dog: LoadedDog,
    samples: Samples,
    seed: int = 0,
    draws: int = DRAWS,
    min_cell: int = MIN_CELL,
) -> DogEvaluation:
    """DOG's metrics on the positive samples of `samples` (module docstring)."""
    from scipy.stats import wasserstein_distance

    positives = samples.take(samples.hit)
    if len(positives) == 0:
        raise ValueError("no damaging samples to evaluate DOG on")
    reconstructed, reconstructed_group = dog_reconstruct(dog, positives, seed)
    generated, generated_group = dog_generate(dog, positives, seed + 1, draws)
    real = positives.damage.astype(np.float64)
    real_group = positives.hit_group.astype(np.int64)
    generated_weapon = np.tile(positives.attacker_weapon, draws)
    cells = wasserstein_cells(
        positives.attacker_weapon,
        real_group,
        real,
        generated_weapon,
        generated_group.ravel(),
        generated.ravel(),
        min_cell,
    )
    regression = regression_metrics(real, reconstructed)
    metrics: dict[str, Any] = {
        "samples": len(positives),
        "damage_mae_hp": regression["mae"],
        "damage_r2": regression["r2"],
        "hit_group_accuracy": float(np.mean(reconstructed_group == real_group)),
        "hit_group_accuracy_generated": float(np.mean(generated_group == real_group[None, :])),
        "generated_mean_damage_hp": float(generated.mean()),
        "real_mean_damage_hp": float(real.mean()),
        "wasserstein_all_hp": float(wasserstein_distance(real, generated.ravel())),
        "mean_wasserstein_hp": float(np.mean([c.wasserstein_hp for c in cells]))
        if cells
        else math.nan,
        "wasserstein_cells": len(cells),
        "min_cell": min_cell,
        "draws": draws,
        "cells": [c.__dict__ for c in cells],
    }
    return DogEvaluation(
        metrics,
        real,
        real_group,
        positives.attacker_weapon.copy(),
        reconstructed,
        reconstructed_group,
        generated.ravel(),
        generated_group.ravel(),
        generated_weapon,
        cells,
    )


# ---- figures ----------------------------------------------------------------------------------


def write_dip_figures(evaluation: DipEvaluation, folder: Path, title: str = "DIP") -> list[Path]:
    """`dip_curves.png`: the ROC and precision-recall curves, the threshold marked."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    labels, scores = evaluation.labels, evaluation.probabilities
    metrics = evaluation.metrics
    fig, (roc, pr) = plt.subplots(1, 2, figsize=(9, 4))
    fpr, tpr = roc_curve(labels, scores)
    roc.plot(fpr, tpr, color="C0")
    roc.plot([0, 1], [0, 1], color="grey", lw=0.8, ls="--")
    predicted = scores >= metrics["threshold"]
    negatives, positives = max(int((~labels).sum()), 1), max(int(labels.sum()), 1)
    roc.plot(
        np.sum(predicted & ~labels) / negatives,
        np.sum(predicted & labels) / positives,
        "o",
        color="C3",
        label=f"threshold {metrics['threshold']:.3f}",
    )
    roc.set(xlabel="false positive rate", ylabel="true positive rate")
    roc.set_title(f"ROC, AUC {metrics['roc_auc']:.3f}")
    roc.legend(loc="lower right")
    recall, precision = precision_recall_curve(labels, scores)
    pr.step(recall, precision, where="post", color="C0")
    pr.axhline(labels.mean(), color="grey", lw=0.8, ls="--")
    pr.set(xlabel="recall", ylabel="precision", ylim=(0, 1.02))
    pr.set_title(f"precision-recall, AP {metrics['average_precision']:.3f}")
    fig.suptitle(f"{title}: {len(labels):,} samples ({int(labels.sum()):,} positive)")
    path = folder / "dip_curves.png"
    save_figure(fig, path)
    return [path]


def write_dog_figures(
    evaluation: DogEvaluation, folder: Path, title: str = "DOG", panels: int = 9
) -> list[Path]:
    """Reconstructed vs real damage, the error histogram, the hit-group confusion matrix, and
    generated vs real damage in the `panels` most frequent (weapon, hit group) cells."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    e = evaluation
    paths = []

    fig, ax = plt.subplots(figsize=(5, 5))
    ax.scatter(e.real_damage, e.reconstructed_damage, s=8, alpha=0.5)
    top = max(float(e.real_damage.max()), float(e.reconstructed_damage.max()), 1.0)
    ax.plot([0, top], [0, top], color="grey", lw=0.8, ls="--")
    ax.set(xlabel="real damage (HP)", ylabel="reconstructed damage (HP)")
    ax.set_title(
        f"{title} reconstruction: MAE {e.metrics['damage_mae_hp']:.2f} HP, "
        f"R² {e.metrics['damage_r2']:.3f}"
    )
    paths.append(folder / "dog_reconstruction.png")
    save_figure(fig, paths[-1])

    fig, ax = plt.subplots(figsize=(6, 4))
    ax.hist(e.reconstructed_damage - e.real_damage, bins=40, color="C0")
    ax.axvline(0, color="grey", lw=0.8)
    ax.set(xlabel="reconstructed - real damage (HP)", ylabel="samples")
    ax.set_title(f"{title}: reconstruction error ({len(e.real_damage):,} samples)")
    paths.append(folder / "dog_error_histogram.png")
    save_figure(fig, paths[-1])

    matrix = confusion_matrix(e.real_group, e.reconstructed_group, len(HIT_GROUPS))
    fig, ax = plt.subplots(figsize=(5.5, 5))
    shares = matrix / np.maximum(matrix.sum(axis=1, keepdims=True), 1)
    ax.imshow(shares, cmap="Blues", vmin=0, vmax=1)
    for (i, j), count in np.ndenumerate(matrix):
        ax.text(j, i, str(count), ha="center", va="center", color="black", fontsize=8)
    ax.set_xticks(range(len(HIT_GROUPS)), HIT_GROUPS, rotation=45)
    ax.set_yticks(range(len(HIT_GROUPS)), HIT_GROUPS)
    ax.set(xlabel="reconstructed hit group", ylabel="real hit group")
    ax.set_title(f"{title}: hit groups, accuracy {e.metrics['hit_group_accuracy']:.3f}")
    paths.append(folder / "dog_hit_group_confusion.png")
    save_figure(fig, paths[-1])

    paths.append(folder / "dog_generated_vs_real.png")
    _generated_vs_real(e, paths[-1], title, panels)
    return paths


def _generated_vs_real(e: DogEvaluation, path: Path, title: str, panels: int) -> None:
    """Small multiples: real and generated damage histograms of the most frequent cells."""
    import matplotlib.pyplot as plt
    from scipy.stats import wasserstein_distance

    cells: list[tuple[str, int, int]] = []
    for weapon in np.unique(e.weapon):
        for code in range(len(HIT_GROUPS)):
            count = int(np.sum((e.weapon == weapon) & (e.real_group == code)))
            if count:
                cells.append((str(weapon), code, count))
    cells.sort(key=lambda c: (-c[2], c[0], c[1]))
    cells = cells[:panels]
    columns = min(3, len(cells))
    rows = math.ceil(len(cells) / columns)
    fig, axes = plt.subplots(
        rows, columns, figsize=(3.4 * columns, 2.6 * rows), squeeze=False, sharex=True
    )
    bins = np.linspace(0, MAX_DAMAGE_HP, 21)
    for ax, (weapon, code, count) in zip(axes.ravel(), cells, strict=False):
        real = e.real_damage[(e.weapon == weapon) & (e.real_group == code)]
        generated = e.generated_damage[(e.generated_weapon == weapon) & (e.generated_group == code)]
        ax.hist(real, bins=bins, density=True, alpha=0.6, label=f"real ({count})")
        if len(generated):
            ax.hist(
                generated,
                bins=bins,
                density=True,
                histtype="step",
                lw=1.5,
                label=f"generated ({len(generated)})",
            )
        distance = wasserstein_distance(real, generated) if len(generated) else math.nan
        ax.set_title(f"{weapon}, {HIT_GROUPS[code]}: W {distance:.1f} HP", fontsize=9)
        ax.legend(fontsize=7)
    for ax in axes.ravel()[len(cells) :]:
        ax.axis("off")
    for ax in axes[-1]:
        ax.set_xlabel("damage (HP)")
    fig.suptitle(f"{title}: generated vs real damage, most frequent weapon and hit-group cells")
    fig.tight_layout()
    save_figure(fig, path)
