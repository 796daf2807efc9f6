"""The numbers of the damage models' evaluation, plain numpy (scipy for the Wasserstein):
ROC AUC, average precision, their curves, the best-F1 threshold, classification and regression
metrics, the confusion matrix and the Wasserstein distance per (weapon, hit group or distance
band) cell.

No scikit-learn: these few metrics do not justify the dependency, and each is checked by hand
in tests/test_damage_evaluation.py.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TypedDict

import numpy as np

from decoy_cli.damage.features import HIT_GROUPS

MIN_CELL = 10
"""Fewest real samples a (weapon, hit group) cell needs to enter the mean Wasserstein."""


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
    labels: np.ndarray, scores: np.ndarray, threshold: float | np.ndarray
) -> dict[str, float]:
    """Accuracy, precision, recall and F1 at `threshold` (positive at or above it), ROC AUC,
    average precision, the threshold and the class counts. `threshold` may be an array, one
    per sample (samples scored by several classifiers, each at its own): the threshold given
    is then NaN."""
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
        "threshold": float(threshold) if np.ndim(threshold) == 0 else math.nan,
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


class CellRecord(TypedDict):
    """A `Cell` as its reports write it."""

    weapon: str
    part: str
    real: int
    generated: int
    wasserstein_hp: float


@dataclass(frozen=True)
class Cell:
    """One (weapon, part) cell, the part a hit group or a distance band: sample counts and the
    Wasserstein distance in HP."""

    weapon: str
    part: str
    real: int
    generated: int
    wasserstein_hp: float

    def record(self) -> CellRecord:
        return {
            "weapon": self.weapon,
            "part": self.part,
            "real": self.real,
            "generated": self.generated,
            "wasserstein_hp": self.wasserstein_hp,
        }


def group_names(codes: np.ndarray) -> np.ndarray:
    """Hit-group codes as their names ("" for a code outside HIT_GROUPS)."""
    names = np.array([*HIT_GROUPS, ""], dtype=object)
    codes = np.asarray(codes, dtype=np.int64)
    return names[np.where((codes >= 0) & (codes < len(HIT_GROUPS)), codes, len(HIT_GROUPS))]


def keyed_cells(
    real_weapon: np.ndarray,
    real_part: np.ndarray,
    real_value: np.ndarray,
    generated_weapon: np.ndarray,
    generated_part: np.ndarray,
    generated_value: np.ndarray,
    min_cell: int = MIN_CELL,
) -> list[Cell]:
    """The (weapon, part) cells with at least `min_cell` real and generated samples, most real
    samples first; the parts are labels (hit-group names, distance bands)."""
    from scipy.stats import wasserstein_distance

    real_weapon = np.asarray(real_weapon, dtype=object)
    real_part = np.asarray(real_part, dtype=object)
    generated_weapon = np.asarray(generated_weapon, dtype=object)
    generated_part = np.asarray(generated_part, dtype=object)
    cells = []
    for weapon, part in sorted(
        {(str(w), str(p)) for w, p in zip(real_weapon, real_part, strict=True)}
    ):
        real = real_value[(real_weapon == weapon) & (real_part == part)]
        generated = generated_value[(generated_weapon == weapon) & (generated_part == part)]
        if len(real) >= min_cell and len(generated) >= min_cell:
            distance = float(wasserstein_distance(real, generated))
            cells.append(Cell(weapon, part, len(real), len(generated), distance))
    return sorted(cells, key=lambda c: (-c.real, c.weapon, c.part))


def wasserstein_cells(
    real_weapon: np.ndarray,
    real_group: np.ndarray,
    real_damage: np.ndarray,
    generated_weapon: np.ndarray,
    generated_group: np.ndarray,
    generated_damage: np.ndarray,
    min_cell: int = MIN_CELL,
) -> list[Cell]:
    """`keyed_cells` by (weapon, hit group), the groups given as codes."""
    return keyed_cells(
        real_weapon,
        group_names(real_group),
        real_damage,
        generated_weapon,
        group_names(generated_group),
        generated_damage,
        min_cell,
    )


def sampling_floor(
    cells: list[Cell], weapon: np.ndarray, part: np.ndarray, value: np.ndarray
) -> list[float]:
    """Per cell, the Wasserstein distance the model would score were the real samples drawn from
    it. `weapon` (K,) is each sample's, `part` (D, K) the part label (or hit-group code) and
    `value` (D, K) the value of the model's D draws for each. For each draw d, the model's d-th
    outcome of every sample stands in for the real one (each keeps its own inputs: weapon,
    range, armour), and its cell is compared with the cell of all draws; the floor is the mean
    over d. A cell of a few real samples scores about this much by chance alone: a model cannot
    be told from the real game below it."""
    from scipy.stats import wasserstein_distance

    weapons = np.asarray(weapon, dtype=object)
    part = np.asarray(part)
    labels = group_names(part) if np.issubdtype(part.dtype, np.integer) else part.astype(object)
    floors = []
    for cell in cells:
        of_weapon = weapons == cell.weapon
        drawn, parts = value[:, of_weapon], labels[:, of_weapon]
        pool = drawn[parts == cell.part]
        found = [
            wasserstein_distance(drawn[d][parts[d] == cell.part], pool)
            for d in range(len(drawn))
            if np.any(parts[d] == cell.part)
        ]
        floors.append(float(np.mean(found)) if found else math.nan)
    return floors


def tv_floor(groups: np.ndarray, limit: float = 0.15) -> tuple[float, float]:
    """The hit-group total variation the model would score against real samples drawn from it
    (as `sampling_floor`): `groups` (D, n) are its D draws for the n samples of one weapon; each
    draw's shares against all draws' shares. Returns the mean over draws and the share of draws
    above `limit`."""
    counts = np.stack([np.bincount(row, minlength=len(HIT_GROUPS)) for row in groups])
    pooled = counts.sum(axis=0) / counts.sum()
    tv = 0.5 * np.abs(counts / counts.sum(axis=1, keepdims=True) - pooled).sum(axis=1)
    return float(tv.mean()), float(np.mean(tv > limit))


MIN_WEAPON_SAMPLES = 30
"""Fewest real samples of a weapon for its hit-group total variation."""


def hit_group_tv(
    real_weapon: np.ndarray,
    real_group: np.ndarray,
    generated_weapon: np.ndarray,
    generated_group: np.ndarray,
    min_samples: int = MIN_WEAPON_SAMPLES,
) -> dict[str, float]:
    """Per weapon with at least `min_samples` real samples: the total variation distance
    between the real and the generated hit-group shares (0: the same, 1: disjoint)."""
    out = {}
    for weapon in sorted(set(np.asarray(real_weapon, dtype=object).tolist())):
        real = np.asarray(real_group)[np.asarray(real_weapon, dtype=object) == weapon]
        generated = np.asarray(generated_group)[
            np.asarray(generated_weapon, dtype=object) == weapon
        ]
        if len(real) < min_samples or not len(generated):
            continue
        p = np.bincount(real, minlength=len(HIT_GROUPS)) / len(real)
        q = np.bincount(generated, minlength=len(HIT_GROUPS)) / len(generated)
        out[str(weapon)] = 0.5 * float(np.abs(p - q).sum())
    return out
