"""Where a landed shot hits: a distribution of hit groups learned from real hits.

The game computes a hit's damage (decoy_cli/damage/rules.py); where the bullet lands is chance,
shaped by the weapon and the range. `HitGroupModel` estimates P(group | weapon, distance band) by
backing off from the weapon to its class to all weapons: each level's counts are smoothed toward
the level above with `PRIOR_HITS` pseudo-hits, so a weapon seen a few times takes its class's
shape and a weapon seen often its own. The model is a handful of counts: it fits in milliseconds,
travels as JSON and draws in a batched call.
"""

from __future__ import annotations

import json
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

from decoy_cli.damage.rules import rule_group
from decoy_cli.sim.combat import HIT_GROUPS
from decoy_cli.weapons import WEAPONS

GROUPS = HIT_GROUPS
"""The hit groups, in the simulator's order (the rules name them the same way)."""

DISTANCE_BANDS_U = (500.0, 1000.0, 1500.0)
"""Upper edges of the distance bands (Hammer units); a last band takes everything beyond."""

PRIOR_HITS = 10.0
"""Pseudo-hits with which each level is pulled toward the level above (chosen a priori)."""


def _smoothed(counts: Sequence[float], prior: np.ndarray) -> np.ndarray:
    """Counts pulled toward `prior` with `PRIOR_HITS` pseudo-hits, as probabilities."""
    values = np.asarray(counts, np.float64)
    return (values + PRIOR_HITS * prior) / (values.sum() + PRIOR_HITS)


def band(distance_u: float) -> int:
    """The distance band of a hit."""
    return int(np.searchsorted(DISTANCE_BANDS_U, distance_u, side="right"))


def weapon_class(weapon: str) -> str:
    """awpy's class of a weapon ("Rifle", "Pistols", ...); "" for unknown names."""
    return WEAPONS.get(weapon, ("", 0.0))[0]


@dataclass
class HitGroupModel:
    """Hit counts by (weapon, band), (class, band) and band (module doc)."""

    weapon_counts: dict[str, list[list[float]]] = field(default_factory=dict)
    class_counts: dict[str, list[list[float]]] = field(default_factory=dict)
    band_counts: list[list[float]] = field(
        default_factory=lambda: [[0.0] * len(GROUPS) for _ in range(len(DISTANCE_BANDS_U) + 1)]
    )

    @classmethod
    def fit(
        cls, weapons: Sequence[str], distances_u: Sequence[float], hit_groups: Sequence[str]
    ) -> HitGroupModel:
        """Count the hits; ESTA's group names are folded ("LeftArm" is "Arm")."""
        model = cls()
        bands = len(DISTANCE_BANDS_U) + 1
        for weapon, distance, group in zip(weapons, distances_u, hit_groups, strict=True):
            g = GROUPS.index(rule_group(group))
            b = band(float(distance))
            for table, key in (
                (model.weapon_counts, weapon),
                (model.class_counts, weapon_class(weapon)),
            ):
                table.setdefault(key, [[0.0] * len(GROUPS) for _ in range(bands)])[b][g] += 1
            model.band_counts[b][g] += 1
        return model

    def add(self, weapon: str, distance_u: float, weights: np.ndarray) -> None:
        """Count one hit whose group is known only as `weights` (6,) over `GROUPS`, summing
        to 1: each group gets its share of a hit."""
        bands = len(DISTANCE_BANDS_U) + 1
        b = band(float(distance_u))
        for table, key in (
            (self.weapon_counts, weapon),
            (self.class_counts, weapon_class(weapon)),
        ):
            row = table.setdefault(key, [[0.0] * len(GROUPS) for _ in range(bands)])[b]
            row[:] = [c + float(w) for c, w in zip(row, weights, strict=True)]
        self.band_counts[b] = [
            c + float(w) for c, w in zip(self.band_counts[b], weights, strict=True)
        ]

    def probabilities(self, weapon: str, distance_u: float) -> np.ndarray:
        """(6,) P(group | weapon, distance) in `GROUPS` order (module doc)."""
        b = band(distance_u)
        every_band = np.asarray(self.band_counts, np.float64).sum(axis=0)
        p = (every_band + 1.0) / (every_band.sum() + len(GROUPS))  # every group stays possible
        p = _smoothed(self.band_counts[b], p)
        if weapon_class(weapon) in self.class_counts:
            p = _smoothed(self.class_counts[weapon_class(weapon)][b], p)
        if weapon in self.weapon_counts:
            p = _smoothed(self.weapon_counts[weapon][b], p)
        return p

    def sample(
        self, rng: np.random.Generator, weapons: Sequence[str], distances_u: Sequence[float]
    ) -> list[str]:
        """One hit group per (weapon, distance), drawn from `probabilities`."""
        cache: dict[tuple[str, int], np.ndarray] = {}
        out = []
        for weapon, distance in zip(weapons, distances_u, strict=True):
            key = (weapon, band(float(distance)))
            if key not in cache:
                cache[key] = np.cumsum(self.probabilities(weapon, float(distance)))
            out.append(GROUPS[min(int(np.searchsorted(cache[key], rng.random())), len(GROUPS) - 1)])
        return out

    def to_dict(self) -> dict[str, object]:
        """The counts with the groups, bands and prior they were counted under."""
        return {
            "groups": GROUPS,
            "distance_bands_u": DISTANCE_BANDS_U,
            "prior_hits": PRIOR_HITS,
            "weapon_counts": self.weapon_counts,
            "class_counts": self.class_counts,
            "band_counts": self.band_counts,
        }

    @classmethod
    def from_dict(cls, data: dict) -> HitGroupModel:
        """A model written by `to_dict`; other groups or bands, or counts of another shape or
        negative, are a ValueError."""
        if (
            tuple(data.get("groups", ())) != GROUPS
            or tuple(data.get("distance_bands_u", ())) != DISTANCE_BANDS_U
        ):
            raise ValueError("a hit-group model of other groups or distance bands")
        shape = (len(DISTANCE_BANDS_U) + 1, len(GROUPS))
        tables = [data["band_counts"], *data["weapon_counts"].values()]
        tables += list(data["class_counts"].values())
        for table in tables:
            counts = np.asarray(table, dtype=np.float64)
            if counts.shape != shape or not (np.isfinite(counts).all() and (counts >= 0).all()):
                raise ValueError(f"hit counts must be {shape[0]} x {shape[1]} and not negative")
        return cls(data["weapon_counts"], data["class_counts"], data["band_counts"])

    def to_json(self) -> str:
        return json.dumps(self.to_dict(), sort_keys=True)

    @classmethod
    def from_json(cls, text: str) -> HitGroupModel:
        """`from_dict` of JSON text."""
        return cls.from_dict(json.loads(text))
