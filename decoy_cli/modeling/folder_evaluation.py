"""Scoring any `--models` choice ("rules", "shipped", "paper" or a folder) on ESTA data, as
`decoy models evaluate` does: DIP's metrics, DOG's (on the hits whose raw damage and hit group
the data records), and the HP lost drawn against real by whatever decides the damage (DOG or
rules) per 0.5 s step and, for the rules, per hit, per map (decoy_cli/modeling/hp_lost.py); on all
samples or on one part of a split, written with the figures to an output folder (metrics.json).

DIP is scored on a 1:1 balanced set by default (the paper's). torch is imported when the models
are loaded, not when this module is imported.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from decoy_cli.damage.bullet_counts import ALL, MAX_BULLETS, BulletCounts
from decoy_cli.damage.choice import ModelChoice, ModelName
from decoy_cli.errors import ModelError
from decoy_cli.modeling.damage_rows import group_id
from decoy_cli.modeling.hp_lost import HpLostScores
from decoy_cli.modeling.network_evaluation import DRAWS, DipEvaluation, DogEvaluation
from decoy_cli.modeling.provenance import FileCallback, SampleChoice, write_json
from decoy_cli.modeling.sample_set import Samples, SampleStats
from decoy_cli.modeling.scores import MIN_CELL
from decoy_cli.modeling.split import SplitPart, balance

if TYPE_CHECKING:
    from decoy_cli.damage.model_folder import LoadedDip

DEFAULT_SUBSET: SplitPart = "all"
"""Score on every sample; or "train", "val", "test": that part of the split."""
BALANCED = True
"""DIP is scored on all positives and as many random negatives (the paper's 1:1)."""


@dataclass(frozen=True)
class FolderEvaluation:
    """What scoring a model folder gave: its name, the samples read (`stats` with the
    failures), DIP's and DOG's evaluations (None for a model the folder lacks, or a DOG on data
    without hit groups), the HP lost per step and per hit by map (`hp_lost`: unit -> map ->
    scores; per hit for the rules only), what was left out of the scores and why (`notes`), the
    report written to `out`/metrics.json and the figures."""

    name: str
    subset: SplitPart
    samples: int
    stats: SampleStats
    dip: DipEvaluation | None
    dog: DogEvaluation | None
    hp_lost: dict[str, dict[str, HpLostScores]]
    notes: list[str]
    warnings: list[str]
    """Model parts not trained on every map of the data (`model_maps.map_warnings`)."""
    report: dict[str, object]
    """What metrics.json holds."""
    out: Path
    figures: list[Path]
    dip_by_map: dict[str, dict[str, float]] = field(default_factory=dict)
    """DIP's metrics on each map's samples (`evaluate_dip_by_map`)."""
    dip_name: str = ""
    """The DIP that decides hits (the choice's one, on every map; "" without one)."""


def evaluate_model_folder(
    *,
    models: ModelChoice,
    choice: SampleChoice,
    out: Path,
    subset: SplitPart = DEFAULT_SUBSET,
    balanced: bool = BALANCED,
    threshold: float | None = None,
    draws: int = DRAWS,
    min_cell: int = MIN_CELL,
    on_file: FileCallback | None = None,
) -> FolderEvaluation:
    """Score the DIP and the damage model of the `--models` choice on `choice`'s samples (all,
    or the `subset` part of its split) and write metrics.json and the figures to `out`. A
    folder without models, a bad option, or a subset without damaging samples is one
    ModelError line."""
    from decoy_cli.damage import damages_by_rules, resolve_models

    if models == ModelName.NONE:
        raise ModelError("none: no models to evaluate (none turns shooting off)")
    folder = resolve_models(models)
    by_rules = damages_by_rules(models, folder)
    has_dip = (folder / "dip.json").is_file()
    has_dog = (folder / "dog.json").is_file() and not by_rules
    if not (has_dip or has_dog or by_rules):
        raise ModelError(f"{folder}: holds neither dip.json nor dog.json")
    if threshold is not None and not 0.0 <= threshold <= 1.0:
        raise ModelError(f"--threshold must be a probability in [0, 1], not {threshold}")
    if draws < 1 or min_cell < 1:
        raise ModelError("--draws and --min-cell must be at least 1")
    samples, stats = choice.read(on_file)
    index = np.arange(len(samples)) if subset == "all" else choice.split(samples).part(subset)

    from decoy_cli.damage.model_folder import load_dip, load_dog
    from decoy_cli.damage.model_maps import dip_of, map_warnings
    from decoy_cli.damage.rules_damage import RulesFile
    from decoy_cli.modeling.evaluation_figures import write_dip_figures, write_dog_figures
    from decoy_cli.modeling.hp_lost import draw_outcomes, score_by_map
    from decoy_cli.modeling.network_evaluation import evaluate_dog

    report: dict[str, object] = {
        "models": str(models),
        "model_folder": str(folder),
        "damage_by": "rules" if by_rules else "DOG",
        "data": [str(d) for d in choice.data],
        "subset": subset,
        "split": None if subset == "all" else {"by": choice.split_by, "seed": choice.seed},
        "mode": choice.mode,
        "window_s": choice.window_s,
        "sample_stats": stats.to_json(),
    }
    figures: list[Path] = []
    notes: list[str] = []
    named = models in (ModelName.RULES, ModelName.SHIPPED, ModelName.PAPER)
    name = str(models) if named else folder.name or str(folder)
    dip_result = dog_result = None
    by_map: dict[str, dict[str, float]] = {}
    dip_name = ""
    if has_dip:
        chosen = balance(samples, index, choice.seed) if balanced else index
        if not samples.hit[chosen].any():
            raise ModelError(f"no damaging samples in the {subset} samples: DIP cannot be scored")
        dip = dip_of(models)
        dip_name = dip.name
        dip_result, by_map = evaluate_dip_by_map(load_dip(dip.folder), samples, chosen, threshold)
        report["dip"] = {"balanced": balanced, **dip_result.metrics}
        report["dip_by_map"] = by_map
        report["dip_of_map"] = dict.fromkeys(by_map, dip_name)
        figures += write_dip_figures(dip_result, out, f"DIP of {name}")
    hits = index[samples.hit[index]]
    outcome = RulesFile.load(folder) if by_rules else load_dog(folder) if has_dog else None
    hp_lost: dict[str, dict[str, HpLostScores]] = {}
    if outcome is None:
        notes.append("no DOG and no rules.json: the damage is not scored")
    elif len(hits) == 0:
        raise ModelError(f"no damaging samples in the {subset} samples: damage cannot be scored")
    else:
        positives = samples.take(hits)
        damage, _ = draw_outcomes(outcome, positives, choice.seed, draws)
        hp_lost["step"] = score_by_map(positives, damage, min_cell)
    if isinstance(outcome, RulesFile):
        per_hit = _hit_samples(choice, samples, subset, index)
        if len(per_hit):
            one = BulletCounts({ALL: [1.0] + [0.0] * (MAX_BULLETS - 1)})
            one_bullet = replace(outcome, bullets=one, bullets_hurt=None)
            drawn, _ = draw_outcomes(one_bullet, per_hit, choice.seed, draws)
            hp_lost["hit"] = score_by_map(per_hit, drawn, min_cell)
    elif outcome is not None:
        known = hits[samples.outcome_known[hits]]
        if len(known):
            dog_result = evaluate_dog(outcome, samples.take(known), choice.seed, draws, min_cell)
            report["dog"] = dog_result.metrics
            figures += write_dog_figures(dog_result, out, f"DOG of {name}")
        if len(known) < len(hits):
            notes.append(
                f"DOG by hit group: {len(hits) - len(known)} of {len(hits)} damaging steps left "
                "out (their data records no hit group or raw damage); all are in the HP lost"
            )
        notes.append("per hit: a DOG draws a step's damage, not a bullet's: scored per step only")
    report["hp_lost"] = {
        unit: {where: scores.to_json() for where, scores in of_map.items()}
        for unit, of_map in hp_lost.items()
    }
    report["notes"] = notes
    warnings = map_warnings(models, [str(m) for m in samples.map_name[index]])
    report["warnings"] = warnings
    write_json(out / "metrics.json", report)
    return FolderEvaluation(
        name,
        subset,
        len(samples),
        stats,
        dip_result,
        dog_result,
        hp_lost,
        notes,
        warnings,
        report,
        out,
        figures,
        by_map,
        dip_name,
    )


def evaluate_dip_by_map(
    dip: LoadedDip, samples: Samples, chosen: np.ndarray, threshold: float | None
) -> tuple[DipEvaluation, dict[str, dict[str, float]]]:
    """The `chosen` samples scored by `dip` at the threshold the fight decides by (or
    `threshold`): the evaluation
    of them all, and each map's metrics."""
    from decoy_cli.modeling.network_evaluation import evaluate_dip

    maps = np.array([str(m) for m in samples.map_name[chosen]], dtype=object)
    by_map: dict[str, dict[str, float]] = {}
    for where in sorted(set(maps.tolist())):
        rows = chosen[np.flatnonzero(maps == where)]
        by_map[where] = evaluate_dip(dip, samples.take(rows), threshold).metrics
    return evaluate_dip(dip, samples.take(chosen), threshold), by_map


def _hit_samples(
    choice: SampleChoice, samples: Samples, subset: SplitPart, index: np.ndarray
) -> Samples:
    """One sample per firearm hit of the data's rounds (`events_mode.hit_samples`), of the
    rounds of `subset`'s samples only."""
    from decoy_cli.esta import RoundFailure, collect_match_files, iter_rounds
    from decoy_cli.modeling.events_mode import hit_samples

    groups = set(samples.group[index].tolist())
    parts = []
    files, _ = collect_match_files(choice.data)
    for item in iter_rounds(files):
        if isinstance(item, RoundFailure) or (subset != "all" and group_id(item) not in groups):
            continue
        parts.append(hit_samples(item, SampleStats()))
    return Samples.concat(parts)
