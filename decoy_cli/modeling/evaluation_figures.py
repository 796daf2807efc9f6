"""The figures of a DIP or DOG evaluation (decoy_cli/modeling/network_evaluation.py): ROC and
precision-recall curves; reconstructed vs real damage, the error histogram, the hit-group
confusion matrix and generated vs real damage per cell. matplotlib is imported when drawing.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from decoy_cli.damage.features import HIT_GROUPS
from decoy_cli.figures import save_figure
from decoy_cli.modeling.network_evaluation import DipEvaluation, DogEvaluation
from decoy_cli.modeling.sample_set import MAX_DAMAGE_HP
from decoy_cli.modeling.scores import confusion_matrix, precision_recall_curve, roc_curve


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
