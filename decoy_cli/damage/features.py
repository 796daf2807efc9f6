"""Damage-model input features: the one place they are built, for training and for simulation.

`encode` turns a `CombatBatch` (decoy_cli/sim/combat.py: K visible attacker-victim pairs, in
metres) into the four float32 blocks that feed the four encoder branches of DIP and DOG
(decoy_cli/damage/networks.py). Training code builds a `CombatBatch` from ESTA data and calls
`encode` too, so a model sees the same features in training and in the simulator.

* map (K, 8): one-hot over `MAPS`, the paper's order. A map outside `MAPS` is a ModelError.
* coords (K, 11): positions, view angles, HP, distance and bearing (below).
* weapon (K, 34): one-hot of the attacker's weapon over `WEAPONS`, the paper's 34 firearms in
  awpy spelling, sorted as Python sorts strings (the order of the paper's state dict). It holds
  every firearm `decoy_cli.weapons` knows. Fallback: any other weapon (knife, grenades, C4,
  Zeus x27, none "") gives an all-zero row; `weapon_index` returns -1 for it, and
  `decoy_cli.damage.combat.LearnedDamage` lets such an attacker deal no damage.
* armor (K, 2): the victim has a helmet, the victim has armor (armor > 0); 0 or 1, the paper's
  order.

The 11 coords in the two unit systems of `FeatureSpec.units`:

=====  ==============================================  ============================================
slot   "hammer" (the paper's, for its checkpoints)     "normalised" (the project's own models)
=====  ==============================================  ============================================
0-2    attacker x, y, z in Hammer units                attacker (position - centre) / half extent
3      attacker view yaw (degrees mod 360) / 360       attacker view yaw wrapped to [-180, 180)/180
4-6    victim x, y, z in Hammer units                  victim (position - centre) / half extent
7      victim view yaw (degrees mod 360) / 360         victim's bearing of the attacker / pi
8      attacker HP / 100                               attacker HP / 100
9      3-D distance in Hammer units                    3-D distance in metres / distance scale
10     attacker's bearing of the victim / pi           attacker's bearing of the victim / pi
=====  ==============================================  ============================================

A bearing is the direction from one player to the other (atan2 of the position difference)
minus the first player's view yaw, in radians wrapped to [-pi, pi): 0 straight ahead, positive
to the left (`decoy_cli.geometry.bearing`, the paper's formula). Distance and bearings are
computed here from the positions and yaws (the batch's own `distance`, in metres, is not
read), so no caller can feed a model a distance that disagrees with its positions. Yaws follow
awpy's viewX: degrees, 0 = +x, counter-clockwise; "mod 360" only matters for yaws outside
[0, 360), which awpy never writes.

Why the project normalises: raw Hammer coordinates of several thousand units and distances in
the thousands dominate the first Linear layer of each branch and make training slow and
sensitive to initialisation; features of order one train well without an input normalisation
layer. Positions are centred and scaled by a box (`FeatureSpec.centre_m`, `half_extent_m`; by
default the built-in de_dust2 waypoints' bounding box grown by about 2 m, so a position on the
map lies in [-1, 1]); distance is divided by `distance_scale_m` (50 m, about half the map's
diagonal). The victim's absolute yaw (slot 7 of the paper) becomes its bearing of the attacker:
0 when the victim looks at the shooter, ±1 when it turns its back, which is what matters for
who wins a duel and is continuous where an absolute yaw jumps from 360 to 0. The attacker's yaw
stays absolute (slot 3) so that the layout, and the network, are the paper's.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from decoy_cli.csgo import HAMMER_TO_M
from decoy_cli.errors import ModelError
from decoy_cli.files import JsonObject
from decoy_cli.geometry import bearing, wrap_pi
from decoy_cli.sim.combat import HIT_GROUPS, CombatBatch

MAPS: tuple[str, ...] = (
    "de_ancient",
    "de_dust2",
    "de_inferno",
    "de_train",
    "de_mirage",
    "de_nuke",
    "de_overpass",
    "de_vertigo",
)
"""The eight maps of the paper's models, in the order of their one-hot."""

WEAPONS: tuple[str, ...] = (
    "AK-47",
    "AUG",
    "AWP",
    "CZ75 Auto",
    "Desert Eagle",
    "Dual Berettas",
    "FAMAS",
    "Five-SeveN",
    "G3SG1",
    "Galil AR",
    "Glock-18",
    "M249",
    "M4A1",
    "M4A4",
    "MAC-10",
    "MAG-7",
    "MP5-SD",
    "MP7",
    "MP9",
    "Negev",
    "Nova",
    "P2000",
    "P250",
    "P90",
    "PP-Bizon",
    "R8 Revolver",
    "SCAR-20",
    "SG 553",
    "SSG 08",
    "Sawed-Off",
    "Tec-9",
    "UMP-45",
    "USP-S",
    "XM1014",
)
"""The attackers' weapons of the paper's models (awpy names, `sorted()` order, no Zeus x27)."""

__all__ = [
    "COORDS",
    "DISTANCE_SCALE_M",
    "DUST2_CENTRE_M",
    "DUST2_HALF_EXTENT_M",
    "HIT_GROUPS",
    "MAPS",
    "PAPER_SPEC",
    "UNITS",
    "WEAPONS",
    "FeatureSpec",
    "Features",
    "encode",
    "map_index",
    "weapon_index",
]

COORDS = 11
"""Number of coordinate and angle features."""

UNITS = ("normalised", "hammer", "relative")

DUST2_CENTRE_M = (-4.0, 18.5, -0.3)
"""Centre of the built-in de_dust2 waypoints' bounding box, metres (rounded)."""

DUST2_HALF_EXTENT_M = (40.0, 43.0, 5.0)
"""Half the size of that box grown by about 2 m on every side, metres."""

DISTANCE_SCALE_M = 50.0
"""Distances are divided by this in normalised features (about half de_dust2's diagonal)."""

_WEAPON_INDEX = {name: k for k, name in enumerate(WEAPONS)}
_MAP_INDEX = {name: k for k, name in enumerate(MAPS)}


@dataclass(frozen=True)
class FeatureSpec:
    """How coordinates are expressed: "normalised" (the project's, with its box and distance
    scale) or "hammer" (the paper's raw Hammer units; the constants are then unused)."""

    units: str = "normalised"
    centre_m: tuple[float, float, float] = DUST2_CENTRE_M
    half_extent_m: tuple[float, float, float] = DUST2_HALF_EXTENT_M
    distance_scale_m: float = DISTANCE_SCALE_M

    def __post_init__(self) -> None:
        if self.units not in UNITS:
            raise ModelError(f"unknown feature units {self.units!r} ({', '.join(UNITS)})")
        centre = tuple(float(x) for x in self.centre_m)
        half = tuple(float(x) for x in self.half_extent_m)
        if len(centre) != 3 or not all(math.isfinite(x) for x in centre):
            raise ModelError(f"feature centre must be 3 finite numbers, got {self.centre_m!r}")
        if len(half) != 3 or not all(math.isfinite(x) and x > 0 for x in half):
            raise ModelError(
                f"feature half extent must be 3 positive numbers, got {self.half_extent_m!r}"
            )
        scale = float(self.distance_scale_m)
        if not (math.isfinite(scale) and scale > 0):
            raise ModelError(f"feature distance scale must be positive, got {scale!r}")
        object.__setattr__(self, "centre_m", centre)
        object.__setattr__(self, "half_extent_m", half)
        object.__setattr__(self, "distance_scale_m", scale)

    def to_json(self) -> JsonObject:
        """The spec as a JSON-ready dict (the constants only for normalised units)."""
        if self.units == "hammer":
            return {"units": "hammer"}
        return {
            "units": self.units,
            "centre_m": list(self.centre_m),
            "half_extent_m": list(self.half_extent_m),
            "distance_scale_m": self.distance_scale_m,
        }

    @classmethod
    def from_json(cls, data: object) -> FeatureSpec:
        """The spec of a `to_json` dict; anything else is a ModelError."""
        if not isinstance(data, dict) or "units" not in data:
            raise ModelError("feature spec must be an object with 'units'")
        units = data["units"]
        if units == "hammer":
            return cls(units="hammer")
        keys = ("centre_m", "half_extent_m", "distance_scale_m")
        missing = [key for key in keys if key not in data]
        if units == "normalised" and missing:
            raise ModelError(f"normalised feature spec lacks {', '.join(missing)}")
        try:
            return cls(
                units=str(units),
                centre_m=tuple(data.get("centre_m", DUST2_CENTRE_M)),
                half_extent_m=tuple(data.get("half_extent_m", DUST2_HALF_EXTENT_M)),
                distance_scale_m=data.get("distance_scale_m", DISTANCE_SCALE_M),
            )
        except (TypeError, ValueError) as error:
            raise ModelError(f"bad feature spec: {error}") from None


PAPER_SPEC = FeatureSpec(units="hammer")
"""The features of the paper's published checkpoints."""


@dataclass(frozen=True)
class Features:
    """Model inputs of K pairs, float32: map (K, 8), coords (K, 11), weapon (K, 34) and
    armor (K, 2)."""

    map: np.ndarray
    coords: np.ndarray
    weapon: np.ndarray
    armor: np.ndarray

    def __post_init__(self) -> None:
        widths = {"map": len(MAPS), "coords": COORDS, "weapon": len(WEAPONS), "armor": 2}
        rows = {len(getattr(self, name)) for name in widths}
        for name, width in widths.items():
            block = np.asarray(getattr(self, name), dtype=np.float32)
            if block.ndim != 2 or block.shape[1] != width:
                raise ValueError(f"features {name} must be (K, {width}), got {block.shape}")
            object.__setattr__(self, name, block)
        if len(rows) != 1:
            raise ValueError(f"feature blocks of different lengths {sorted(rows)}")

    def __len__(self) -> int:
        return len(self.coords)

    def take(self, index: np.ndarray | Sequence[int] | slice) -> Features:
        """The rows at `index` (integer indices, a boolean mask or a slice)."""
        return Features(self.map[index], self.coords[index], self.weapon[index], self.armor[index])

    @staticmethod
    def concat(parts: Sequence[Features]) -> Features:
        """The rows of all parts, in order (no parts: zero rows)."""
        if not parts:
            return _empty()
        return Features(
            np.concatenate([p.map for p in parts]),
            np.concatenate([p.coords for p in parts]),
            np.concatenate([p.weapon for p in parts]),
            np.concatenate([p.armor for p in parts]),
        )


def _empty() -> Features:
    return Features(
        np.zeros((0, len(MAPS)), np.float32),
        np.zeros((0, COORDS), np.float32),
        np.zeros((0, len(WEAPONS)), np.float32),
        np.zeros((0, 2), np.float32),
    )


def map_index(name: str) -> int:
    """Index of a map in `MAPS`; a ModelError for a map the models do not know."""
    try:
        return _MAP_INDEX[name]
    except KeyError:
        raise ModelError(
            f"the damage models know no map {name!r} (they know {', '.join(MAPS)})"
        ) from None


def weapon_index(names: np.ndarray | Sequence[str]) -> np.ndarray:
    """(K,) int64 index of each weapon name in `WEAPONS`, -1 for a name outside it."""
    return np.fromiter((_WEAPON_INDEX.get(str(n), -1) for n in names), np.int64, len(names))


def encode(batch: CombatBatch, spec: FeatureSpec) -> Features:
    """The features of every pair of the batch (see the module docstring).

    Raises ModelError for a map outside `MAPS` and for pairs whose positions, yaws or HP are not
    finite (so no NaN ever reaches a network).
    """
    k = len(batch)
    m = map_index(batch.map_name)
    attacker = np.asarray(batch.attacker_position, dtype=np.float64).reshape(k, 3)
    victim = np.asarray(batch.victim_position, dtype=np.float64).reshape(k, 3)
    attacker_yaw = np.asarray(batch.attacker_yaw, dtype=np.float64).reshape(k)
    victim_yaw = np.asarray(batch.victim_yaw, dtype=np.float64).reshape(k)
    hp = np.asarray(batch.attacker_hp, dtype=np.float64).reshape(k)
    delta = victim - attacker
    seen_by_attacker = bearing(delta[:, 0], delta[:, 1], attacker_yaw)

    coords = np.empty((k, COORDS), dtype=np.float64)
    if spec.units == "hammer":
        coords[:, 0:3] = attacker / HAMMER_TO_M
        coords[:, 3] = np.mod(attacker_yaw, 360.0) / 360.0
        coords[:, 4:7] = victim / HAMMER_TO_M
        coords[:, 7] = np.mod(victim_yaw, 360.0) / 360.0
        coords[:, 9] = np.linalg.norm(delta / HAMMER_TO_M, axis=1)
    else:
        centre = np.asarray(spec.centre_m)
        half = np.asarray(spec.half_extent_m)
        coords[:, 0:3] = (attacker - centre) / half
        coords[:, 3] = wrap_pi(np.radians(attacker_yaw)) / np.pi
        coords[:, 4:7] = (victim - centre) / half
        if spec.units == "relative":  # nothing that names a place on one map
            coords[:, 0:7] = 0.0
            coords[:, 2] = delta[:, 2] / half[2]
        coords[:, 7] = bearing(-delta[:, 0], -delta[:, 1], victim_yaw) / np.pi
        coords[:, 9] = np.linalg.norm(delta, axis=1) / spec.distance_scale_m
    coords[:, 8] = hp / 100.0
    coords[:, 10] = seen_by_attacker / np.pi
    bad = ~np.all(np.isfinite(coords), axis=1)
    if np.any(bad):
        raise ModelError(
            f"{int(bad.sum())} of {k} pairs have a NaN or infinite position, yaw or HP"
        )

    map_onehot = np.zeros((k, len(MAPS)), dtype=np.float32)
    if spec.units != "relative":
        map_onehot[:, m] = 1.0
    weapon = np.zeros((k, len(WEAPONS)), dtype=np.float32)
    index = weapon_index(np.asarray(batch.attacker_weapon).reshape(k))
    known = np.flatnonzero(index >= 0)
    weapon[known, index[known]] = 1.0
    armor = np.stack(
        [
            np.asarray(batch.victim_helmet, dtype=bool).reshape(k),
            np.asarray(batch.victim_armor, dtype=np.float64).reshape(k) > 0,
        ],
        axis=1,
    ).astype(np.float32)
    return Features(map_onehot, coords.astype(np.float32), weapon, armor)
