"""The training samples of DIP and DOG as one container, and what building them counted.

`Samples` holds K (attacker, victim, step) samples as parallel arrays; it turns them into the
simulator's `CombatBatch` and into model inputs (`features`) in the one place that encoding
happens for training and evaluation. How rounds become samples: decoy_cli/modeling/samples.py.
"""

from __future__ import annotations

from collections import Counter
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

from decoy_cli.csgo import BUILTIN_MAP
from decoy_cli.damage.features import Features, FeatureSpec, encode
from decoy_cli.esta import RoundFailure
from decoy_cli.sim.combat import PAIR_FIELDS, CombatBatch

MAX_DAMAGE_HP = 100.0
"""DOG's damage target is capped here (decoy_cli/modeling/damage_rows.py says why)."""


@dataclass(frozen=True, eq=False)
class Samples:
    """K samples: the pair state (metres, degrees), the labels and the group of each.

    `damage` is the raw HP damage (0 for a negative, NaN for a hit whose data lacks it),
    `hp_lost` the HP the victim lost (capped by its HP, as recorded), `hit_group` a code into
    HIT_GROUPS (-1 for a negative, or a hit whose data lacks it),
    `group` "MATCH rROUND", `match` the match id, `tick` the step's tick, `mode` "frames" or
    "events" (how the sample's round was read).
    """

    map_name: np.ndarray  # (K,) str
    attacker_position: np.ndarray  # (K, 3) float64 metres
    victim_position: np.ndarray  # (K, 3) float64 metres
    attacker_yaw: np.ndarray  # (K,) float64 degrees
    victim_yaw: np.ndarray  # (K,) float64 degrees
    attacker_hp: np.ndarray  # (K,) int16
    victim_hp: np.ndarray  # (K,) int16
    attacker_weapon: np.ndarray  # (K,) str
    victim_armor: np.ndarray  # (K,) int16
    victim_helmet: np.ndarray  # (K,) bool
    hit: np.ndarray  # (K,) bool
    damage: np.ndarray  # (K,) float32 HP
    hp_lost: np.ndarray  # (K,) float32 HP
    hit_group: np.ndarray  # (K,) int8
    group: np.ndarray  # (K,) str
    match: np.ndarray  # (K,) str
    tick: np.ndarray  # (K,) int64
    mode: np.ndarray  # (K,) str

    def __len__(self) -> int:
        return len(self.hit)

    @property
    def outcome_known(self) -> np.ndarray:
        """(K,) bool: the hits whose raw damage and hit group are known (what a DOG learns
        from and is scored on by hit group)."""
        return self.hit & (self.hit_group >= 0) & np.isfinite(self.damage)

    def take(self, index: np.ndarray | slice) -> Samples:
        """The samples at `index` (integer indices, a boolean mask or a slice)."""
        return Samples(**{name: getattr(self, name)[index] for name in _FIELDS})

    @staticmethod
    def concat(parts: Sequence[Samples]) -> Samples:
        """All samples of the parts, in order."""
        if not parts:
            return empty_samples()
        return Samples(
            **{name: np.concatenate([getattr(p, name) for p in parts]) for name in _FIELDS}
        )

    def batch(self, index: np.ndarray | None = None) -> CombatBatch:
        """The samples (all, or those at `index`, which must share one map) as a CombatBatch;
        attacker and victim indices are the sample numbers."""
        rows = np.arange(len(self)) if index is None else np.asarray(index)
        maps = np.unique(self.map_name[rows])
        if len(maps) > 1:
            raise ValueError(f"a CombatBatch holds one map, these samples hold {len(maps)}")
        return CombatBatch(
            attacker=rows.astype(np.int64),
            victim=rows.astype(np.int64),
            **{name: getattr(self, name)[rows] for name in PAIR_FIELDS},
            map_name=str(maps[0]) if len(maps) else BUILTIN_MAP,
        )

    def features(self, spec: FeatureSpec) -> Features:
        """The model inputs of every sample, encoded one map at a time by `encode`."""
        if len(self) == 0:
            return encode(self.batch(), spec)
        parts: list[Features] = []
        order: list[np.ndarray] = []
        for name in np.unique(self.map_name):
            rows = np.flatnonzero(self.map_name == name)
            parts.append(encode(self.batch(rows), spec))
            order.append(rows)
        features = Features.concat(parts)
        back = np.empty(len(self), dtype=np.int64)
        back[np.concatenate(order)] = np.arange(len(self))
        return features.take(back)


_FIELDS = tuple(Samples.__dataclass_fields__)


def empty_samples() -> Samples:
    return Samples(
        map_name=np.zeros(0, dtype=object),
        attacker_position=np.zeros((0, 3)),
        victim_position=np.zeros((0, 3)),
        attacker_yaw=np.zeros(0),
        victim_yaw=np.zeros(0),
        attacker_hp=np.zeros(0, np.int16),
        victim_hp=np.zeros(0, np.int16),
        attacker_weapon=np.zeros(0, dtype=object),
        victim_armor=np.zeros(0, np.int16),
        victim_helmet=np.zeros(0, bool),
        hit=np.zeros(0, bool),
        damage=np.zeros(0, np.float32),
        hp_lost=np.zeros(0, np.float32),
        hit_group=np.zeros(0, np.int8),
        group=np.zeros(0, dtype=object),
        match=np.zeros(0, dtype=object),
        tick=np.zeros(0, np.int64),
        mode=np.zeros(0, dtype=object),
    )


@dataclass
class SampleStats:
    """What building the samples used and left out."""

    files: int = 0
    rounds_frames: int = 0
    rounds_events: int = 0
    rounds_without_samples: int = 0
    failures: list[RoundFailure] = field(default_factory=list)
    excluded: Counter[str] = field(default_factory=Counter)
    partial: Counter[str] = field(default_factory=Counter)
    """Hits kept with part of their outcome missing, by what they lack (damage_rows.py)."""
    realigned: int = 0
    positives: int = 0
    negatives: int = 0

    @property
    def round_errors(self) -> int:
        """How many rounds (not whole files) failed: broken in the file, or their samples."""
        return sum(1 for f in self.failures if f.round_num is not None)

    @property
    def file_errors(self) -> int:
        """How many files gave no rounds at all (unreadable, or another map)."""
        return sum(1 for f in self.failures if f.round_num is None)

    def merge(self, other: SampleStats) -> None:
        """Add the counts of `other` (one round's) to these."""
        self.rounds_frames += other.rounds_frames
        self.rounds_events += other.rounds_events
        self.rounds_without_samples += other.rounds_without_samples
        self.failures.extend(other.failures)
        self.excluded.update(other.excluded)
        self.partial.update(other.partial)
        self.realigned += other.realigned

    def to_json(self) -> dict[str, object]:
        """The counts, and every failure, as a JSON-ready dict."""
        return {
            "files": self.files,
            "rounds_frames": self.rounds_frames,
            "rounds_events": self.rounds_events,
            "rounds_without_samples": self.rounds_without_samples,
            "round_errors": self.round_errors,
            "file_errors": self.file_errors,
            "excluded_damage_rows": dict(sorted(self.excluded.items())),
            "partial_damage_rows": dict(sorted(self.partial.items())),
            "realigned_hits": self.realigned,
            "positives": self.positives,
            "negatives": self.negatives,
            "failures": [f.row() for f in self.failures],
        }


def samples_from_rows(rows: list[dict[str, object]]) -> Samples:
    """Samples from one dict of field values per sample."""
    if not rows:
        return empty_samples()
    dtypes = {
        "attacker_position": np.float64,
        "victim_position": np.float64,
        "attacker_yaw": np.float64,
        "victim_yaw": np.float64,
        "attacker_hp": np.int16,
        "victim_hp": np.int16,
        "victim_armor": np.int16,
        "victim_helmet": bool,
        "hit": bool,
        "damage": np.float32,
        "hp_lost": np.float32,
        "hit_group": np.int8,
        "tick": np.int64,
    }
    return Samples(
        **{
            name: np.array([row[name] for row in rows], dtype=dtypes.get(name, object))
            for name in _FIELDS
        }
    )
