"""How good a DIP and a DOG are on samples: the networks run over samples, and the paper's
metrics of what they say (the numbers themselves: scores.py; the figures:
evaluation_figures.py).

DIP (a classifier of "does the attacker damage the victim in this step"): accuracy, precision,
recall and F1 at the decision threshold, ROC AUC and average precision over all thresholds, and
how calibrated its probabilities are: Brier score and expected calibration error
(decoy_cli/damage/calibration.py).
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

torch and scipy.stats are imported by the functions that use them: the CLI imports this
module for its constants and should start quickly.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING, TypedDict

import numpy as np

from decoy_cli.damage.features import HIT_GROUPS
from decoy_cli.modeling.calibration_fit import calibration_scores
from decoy_cli.modeling.sample_set import MAX_DAMAGE_HP, Samples
from decoy_cli.modeling.scores import (
    MIN_CELL,
    Cell,
    CellRecord,
    classification_metrics,
    hit_group_tv,
    regression_metrics,
    wasserstein_cells,
)

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

DRAWS = 10
"""Generated samples per test condition in generative mode."""

_BATCH = 65_536


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
    """DIP's metrics on the samples at `threshold` (default: the one the combat step decides by,
    `LoadedDip.decision_threshold`)."""
    if len(samples) == 0:
        raise ValueError("no samples to evaluate DIP on")
    probabilities = dip_probabilities(dip, samples)
    chosen = dip.decision_threshold if threshold is None else threshold
    metrics = classification_metrics(samples.hit, probabilities, chosen)
    metrics |= calibration_scores(samples.hit, probabilities, dip.calibration)
    return DipEvaluation(metrics, samples.hit.copy(), probabilities)


class DogMetrics(TypedDict):
    """DOG's metrics (module docstring), as `evaluate_dog` reports them."""

    samples: int
    damage_mae_hp: float
    damage_r2: float
    hit_group_accuracy: float
    hit_group_accuracy_generated: float
    generated_mean_damage_hp: float
    real_mean_damage_hp: float
    wasserstein_all_hp: float
    mean_wasserstein_hp: float
    wasserstein_cells: int
    hit_group_tv: dict[str, float]
    min_cell: int
    draws: int
    cells: list[CellRecord]


@dataclass(frozen=True)
class DogEvaluation:
    """DOG's metrics on positive samples and the values behind them (damage in HP)."""

    metrics: DogMetrics
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
    """DOG's metrics on the hits of `samples` whose raw damage and hit group are known (module
    docstring)."""
    from scipy.stats import wasserstein_distance

    positives = samples.take(samples.outcome_known)
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
    metrics: DogMetrics = {
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
        "hit_group_tv": hit_group_tv(
            positives.attacker_weapon, real_group, generated_weapon, generated_group.ravel()
        ),
        "min_cell": min_cell,
        "draws": draws,
        "cells": [c.record() for c in cells],
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
