"""Damage outcome models side by side on the same leave-rounds-out folds of real damaging steps.

The unit is the DOG's: one damaging (attacker, victim, 0.5 s step) sample of the events mode, its
damage summed over the step's hits (capped at 100 HP) and its hit group that of the largest hit.
The rounds are dealt into `FOLDS` folds; each fold's samples are generated (`DRAWS` draws each)
by each model:

* "rules": the rules-grounded model (decoy_cli/damage/rules_damage.py) with its learned parts
  fitted on the other folds' rounds only;
* a model folder's DOG (e.g. the paper's checkpoint, trained on other matches): the same network
  for every fold, honest on rounds it never saw;
* with `cvae` given (training options, loss weights, features), the project's CVAE trained anew
  for every fold on three of the other folds, the fourth stopping it early, as `decoy train dog`
  trains the shipped one.

Pooled over the folds (every sample a test sample once): the mean Wasserstein distance per
(weapon, hit group) cell with at least `MIN_CELL` real samples (the paper's generative protocol,
`decoy_cli/modeling/scores.wasserstein_cells`) and its largest cell, the hit-group total variation
per weapon with at least 30 samples (`scores.hit_group_tv`), and the spread of the per-fold means.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from decoy_cli.damage.features import FeatureSpec
from decoy_cli.esta import Round
from decoy_cli.files import JsonObject
from decoy_cli.modeling.network_evaluation import DRAWS
from decoy_cli.modeling.provenance import seen_in
from decoy_cli.modeling.rules_fit import fit_rules
from decoy_cli.modeling.sample_set import Samples
from decoy_cli.modeling.scores import hit_group_tv, sampling_floor, wasserstein_cells
from decoy_cli.modeling.split import FOLDS, deal_folds
from decoy_cli.modeling.train_options import DogLossWeights, TrainOptions

MIN_CELL = 5
"""Fewest real samples of a cell in the Wasserstein mean of the fold comparison."""


@dataclass(frozen=True)
class CvaeTraining:
    """How to train the project's CVAE in each fold (module doc)."""

    options: TrainOptions
    weights: DogLossWeights
    spec: FeatureSpec


def _cvae_per_fold(
    positives: Samples, fold: np.ndarray, cvae: CvaeTraining, seed: int, draws: int
) -> tuple[np.ndarray, np.ndarray]:
    from typing import cast

    from decoy_cli.damage.model_folder import LoadedDog
    from decoy_cli.damage.networks import DogNet
    from decoy_cli.modeling.network_evaluation import dog_generate
    from decoy_cli.modeling.training import train_dog

    damage = np.zeros((draws, len(positives)))
    group = np.zeros((draws, len(positives)), dtype=np.int64)
    for k in range(FOLDS):
        test = np.flatnonzero(fold == k)
        if not len(test):
            continue
        val = np.flatnonzero(fold == (k + 1) % FOLDS)
        train = np.flatnonzero((fold != k) & (fold != (k + 1) % FOLDS))
        t, v = positives.take(train), positives.take(val)
        trained = train_dog(
            t.features(cvae.spec),
            t.damage,
            t.hit_group,
            v.features(cvae.spec),
            v.damage,
            v.hit_group,
            cvae.options,
            cvae.weights,
        )
        model = LoadedDog(cast(DogNet, trained.net), cvae.spec)
        damage[:, test], group[:, test] = dog_generate(model, positives.take(test), seed + k, draws)
    return damage, group


@dataclass(frozen=True)
class ModelScores:
    """One model's pooled and per-fold results."""

    name: str
    mean_wasserstein_hp: float
    max_wasserstein_hp: float
    cells: int
    fold_means: list[float]
    group_tv: dict[str, float]
    """weapon -> total variation of the real and generated hit-group shares."""
    mean_floor_hp: float
    """The mean over the pooled cells of `scores.sampling_floor`: what this model would score
    were the real samples drawn from it."""


def _score(
    name: str,
    real: Samples,
    damage: np.ndarray,
    group: np.ndarray,
    fold_of_sample: np.ndarray,
) -> ModelScores:
    """Metrics of (draws, K) generated damage and groups against the K real samples."""
    draws = damage.shape[0]
    weapon = np.asarray(real.attacker_weapon, dtype=object)

    def cells(index: np.ndarray) -> list:
        return wasserstein_cells(
            weapon[index],
            real.hit_group[index],
            real.damage[index],  # capped at 100 HP when the samples were made
            np.tile(weapon[index], draws),
            group[:, index].ravel(),
            damage[:, index].ravel(),
            min_cell=MIN_CELL,
        )

    pooled = cells(np.arange(len(real)))
    fold_means = []
    for fold in np.unique(fold_of_sample):
        found = cells(np.flatnonzero(fold_of_sample == fold))
        if found:
            fold_means.append(float(np.mean([c.wasserstein_hp for c in found])))
    tv = hit_group_tv(weapon, real.hit_group, np.tile(weapon, draws), group.ravel())
    values = [c.wasserstein_hp for c in pooled]
    floors = sampling_floor(pooled, weapon, group, damage)
    return ModelScores(
        name,
        float(np.mean(values)) if values else float("nan"),
        float(np.max(values)) if values else float("nan"),
        len(values),
        fold_means,
        tv,
        float(np.mean(floors)) if floors else float("nan"),
    )


def rules_out_of_fold(
    rounds: Sequence[Round], positives: Samples, fold: np.ndarray, seed: int, draws: int
) -> tuple[np.ndarray, np.ndarray]:
    """(draws, K) damage and hit-group codes of the K damaging samples, each fold's drawn by
    rules fitted on the rounds of the other folds only (`fold`: each sample's fold)."""
    from decoy_cli.modeling.damage_rows import group_id
    from decoy_cli.modeling.hp_lost import draw_outcomes

    fold_of_group = {str(g): int(f) for g, f in zip(positives.group, fold, strict=True)}
    damage = np.zeros((draws, len(positives)))
    group = np.zeros((draws, len(positives)), dtype=np.int64)
    for k in np.unique(fold):
        test = np.flatnonzero(fold == k)
        train = [r for r in rounds if fold_of_group.get(group_id(r), -1) != k]
        rules = fit_rules(train)
        damage[:, test], group[:, test] = draw_outcomes(
            rules, positives.take(test), seed + int(k), draws
        )
    return damage, group


def training_overlap(metadata: JsonObject, samples: Samples) -> str:
    """What share of the samples' rounds a model saw while it was trained (its training or
    validation part, as its metadata's split records them), in words for a label."""
    seen = seen_in(metadata, samples, ("train", "val"))
    if seen is None:
        return "its training data unrecorded"
    rounds = {str(g): bool(s) for g, s in zip(samples.group, seen, strict=True)}
    overlap = sum(rounds.values())
    if overlap == 0:
        maps = metadata.get("maps")
        names = [str(m) for m in maps] if isinstance(maps, list) else []
        return "trained on none of these rounds" + (f" ({', '.join(names)})" if names else "")
    return f"trained or validated on {overlap} of these {len(rounds)} rounds"


def compare_on_folds(
    rounds: Sequence[Round],
    samples: Samples,
    model_folders: dict[str, Path],
    seed: int = 0,
    draws: int = DRAWS,
    cvae: CvaeTraining | None = None,
) -> list[ModelScores]:
    """Every model's scores on the same folds of the damaging samples (module doc)."""
    from decoy_cli.damage.model_folder import load_dog
    from decoy_cli.modeling.network_evaluation import dog_generate

    positives = samples.take(np.flatnonzero(samples.outcome_known))
    fold_of_group = deal_folds(positives.group.tolist(), np.random.default_rng(seed))
    fold = np.array([fold_of_group[g] for g in positives.group])
    results = []
    damage, group = rules_out_of_fold(rounds, positives, fold, seed, draws)
    results.append(_score("rules (fitted per fold)", positives, damage, group, fold))

    if cvae is not None:
        damage, group = _cvae_per_fold(positives, fold, cvae, seed, draws)
        results.append(_score("project CVAE (trained per fold)", positives, damage, group, fold))

    for name, folder in model_folders.items():
        dog = load_dog(folder)
        damage, group = dog_generate(dog, positives, seed, draws)
        results.append(_score(name, positives, damage, group, fold))
    return results
