"""Damage outcome models scored on the HP their victims lose per 0.5 s step.

Every data set records the HP a hit cost its victim (ESTA's `hpDamageTaken`, capped by the HP the
victim had); not every one records the raw damage or the hit group (`events_ancient` has
neither). So the one score every model and every data set shares is the HP lost per damaging
(attacker, victim, step) sample: the real HP lost summed over the step's hits, against the
model's drawn damage capped by the victim's HP before the step, as the simulator caps it. The
cells are (weapon, distance band) (`hit_groups.DISTANCE_BANDS_U`), so the score needs no hit
group: it is marginalised over them. Beside each cell its sampling floor
(`scores.sampling_floor`), and the mean drawn HP lost against the real.

`draw_outcomes` is the one way a model's damage is drawn for samples: a DOG's generative mode or
the rules-grounded model (`rules_generate`).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np

from decoy_cli.csgo import HAMMER_TO_M
from decoy_cli.damage.hit_groups import DISTANCE_BANDS_U, GROUPS
from decoy_cli.damage.rules_damage import pair_outcome
from decoy_cli.modeling.sample_set import Samples
from decoy_cli.modeling.scores import MIN_CELL, CellRecord, keyed_cells, sampling_floor

if TYPE_CHECKING:
    from decoy_cli.damage.model_folder import LoadedDog
    from decoy_cli.damage.rules_damage import RulesFile

MIN_STEPS = MIN_CELL
"""Fewest real steps of a (weapon, distance band) cell in the mean (`scores.MIN_CELL`)."""

_LOWER = (0.0, *DISTANCE_BANDS_U[:-1])
BANDS = (
    *(f"{lo:.0f}-{hi:.0f} u" for lo, hi in zip(_LOWER, DISTANCE_BANDS_U, strict=True)),
    f"{DISTANCE_BANDS_U[-1]:.0f}+ u",
)
"""The distance bands' labels."""


def distance_u(samples: Samples) -> np.ndarray:
    """(K,) attacker-victim distance in Hammer units."""
    return np.linalg.norm(samples.victim_position - samples.attacker_position, axis=1) / HAMMER_TO_M


def band_labels(distances_u: np.ndarray) -> np.ndarray:
    """(K,) the distance band label of each distance."""
    index = np.searchsorted(DISTANCE_BANDS_U, np.asarray(distances_u, np.float64), side="right")
    return np.asarray(BANDS, dtype=object)[index]


def draw_outcomes(
    model: LoadedDog | RulesFile, samples: Samples, seed: int, draws: int
) -> tuple[np.ndarray, np.ndarray]:
    """`draws` outcomes of each damaging sample: (draws, K) damage in HP, in [1, 100], and
    hit-group codes, from a DOG or the rules."""
    from decoy_cli.damage.rules_damage import RulesFile

    if isinstance(model, RulesFile):
        return rules_generate(
            model,
            [str(w) for w in samples.attacker_weapon],
            distance_u(samples) * HAMMER_TO_M,
            samples.victim_armor,
            samples.victim_helmet,
            samples.victim_hp,
            seed,
            draws,
        )
    from decoy_cli.modeling.network_evaluation import dog_generate

    return dog_generate(model, samples, seed, draws)


def rules_generate(
    rules: RulesFile,
    weapons: Sequence[str],
    distances_m: np.ndarray,
    armor: np.ndarray,
    helmet: np.ndarray,
    victim_hp: np.ndarray,
    seed: int,
    draws: int,
) -> tuple[np.ndarray, np.ndarray]:
    """`draws` outcomes of K damaging pair-steps (victims with `victim_hp` at its start), as
    the DOG's generative mode gives them:
    (draws, K) damage in HP (summed, in [1, 100]) and hit-group codes. A weapon the rules lack
    raises `UnknownWeaponError`."""
    draw = np.random.default_rng(seed)
    damage = np.zeros((draws, len(weapons)))
    group = np.zeros((draws, len(weapons)), dtype=np.int64)
    for d in range(draws):
        for k, weapon in enumerate(weapons):
            health, _, name = pair_outcome(
                rules,
                weapon,
                float(distances_m[k]) / HAMMER_TO_M,
                int(armor[k]),
                bool(helmet[k]),
                draw,
                int(victim_hp[k]),
            )
            damage[d, k] = min(max(health, 1), 100)
            group[d, k] = GROUPS.index(name)
    return damage, group


def drawn_hp_lost(damage: np.ndarray, victim_hp: np.ndarray) -> np.ndarray:
    """(D, K) drawn damage capped by each victim's HP before the step (at least 1)."""
    return np.minimum(damage, np.maximum(np.asarray(victim_hp, np.float64), 1.0)[None, :])


class HpCellRecord(CellRecord):
    """A cell of `HpLostScores`, with its sampling floor."""

    floor_hp: float


@dataclass(frozen=True)
class HpLostScores:
    """HP lost per step, drawn against real, by (weapon, distance band) cell (module doc)."""

    steps: int
    real_mean_hp: float
    drawn_mean_hp: float
    mean_wasserstein_hp: float
    max_wasserstein_hp: float
    mean_floor_hp: float
    steps_in_cells: int
    cells: list[HpCellRecord] = field(default_factory=list)
    """weapon, part (the band), real, generated, wasserstein_hp, floor_hp."""

    def to_json(self) -> dict[str, object]:
        return dict(self.__dict__)


def score_hp_lost(
    weapon: np.ndarray,
    distances_u: np.ndarray,
    real: np.ndarray,
    drawn: np.ndarray,
    min_cell: int = MIN_STEPS,
) -> HpLostScores:
    """Score (D, K) drawn HP lost against the (K,) real HP lost of K steps (module doc)."""
    weapon = np.asarray(weapon, dtype=object)
    draws = drawn.shape[0]
    bands = band_labels(distances_u)
    real = np.asarray(real, np.float64)
    cells = keyed_cells(
        weapon, bands, real, np.tile(weapon, draws), np.tile(bands, draws), drawn.ravel(), min_cell
    )
    floors = sampling_floor(cells, weapon, np.tile(bands, (draws, 1)), drawn)
    values = [c.wasserstein_hp for c in cells]
    return HpLostScores(
        steps=len(real),
        real_mean_hp=float(real.mean()) if len(real) else math.nan,
        drawn_mean_hp=float(drawn.mean()) if drawn.size else math.nan,
        mean_wasserstein_hp=float(np.mean(values)) if values else math.nan,
        max_wasserstein_hp=float(np.max(values)) if values else math.nan,
        mean_floor_hp=float(np.nanmean(floors)) if floors else math.nan,
        steps_in_cells=sum(c.real for c in cells),
        cells=[{**c.record(), "floor_hp": f} for c, f in zip(cells, floors, strict=True)],
    )


def score_by_map(
    positives: Samples, drawn: np.ndarray, min_cell: int = MIN_STEPS
) -> dict[str, HpLostScores]:
    """`score_hp_lost` of the damaging samples of each map, and of all together ("all") when
    they hold more than one map; `drawn` is (D, K) damage of the K samples."""
    hp = drawn_hp_lost(drawn, positives.victim_hp)
    distances = distance_u(positives)
    out = {}
    maps = sorted({str(m) for m in positives.map_name})
    for name in [*maps, "all"] if len(maps) > 1 else maps:
        rows = np.arange(len(positives)) if name == "all" else positives.map_name == name
        out[name] = score_hp_lost(
            positives.attacker_weapon[rows],
            distances[rows],
            positives.hp_lost[rows],
            hp[:, rows],
            min_cell,
        )
    return out
