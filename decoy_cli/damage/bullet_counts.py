"""How many bullets of one pair land in one damaging 0.5 s step: `BulletCounts`, learned from
real steps (`decoy_cli.modeling.rules_fit.fit_rules`).

Steps are counted by the bullets that landed, at four levels, each pulled toward the one above
with `PRIOR_STEPS` pseudo-steps: all steps, the weapon's class, the weapon, and the weapon at
the step's distance band (`hit_groups.DISTANCE_BANDS_U`; fewer bullets land at long range).

A step that killed its victim after k bullets says only that at least k would have landed: the
victim's death ended it. With `censored`, those steps are right-censored and the distribution is
the Kaplan-Meier estimate of the bullets that would land on a victim that stays alive (the
hazard of "no further bullet" at each count, pulled level by level as the counts are), which the
simulator then cuts at the victim's death; the most bullets the weapon was seen to land in one
step (measured on the real steps; a weapon never seen, its class's) bounds it. A step killed at
k goes on past every count below k and leaves the risk set at k: whether it would have ended
there is what its kill hides (counted at risk at k, as if a k+1-th bullet had landed, it drew
too many bullets: a kill by one head shot said "a second bullet lands").
Without `censored`, the plain shares of the counts.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from decoy_cli.damage.hit_groups import band, weapon_class
from decoy_cli.text import shortened

MAX_BULLETS = 10
"""Bullet counts above this are counted as this many."""
PRIOR_STEPS = 5.0
"""Pseudo-steps pulling each level's counts toward the level above (chosen a priori)."""
ALL = "*"


def _keys(weapon: str, distance_u: float) -> list[str]:
    """The table keys from all steps down to the weapon at the distance's band."""
    return [ALL, f"class:{weapon_class(weapon)}", weapon, f"{weapon}@{band(distance_u)}"]


@dataclass
class BulletCounts:
    """Counts of steps by bullets landed (1..MAX_BULLETS) per key (module doc), and of the
    steps among them that killed their victim."""

    counts: dict[str, list[float]] = field(default_factory=dict)
    killed: dict[str, list[float]] = field(default_factory=dict)
    censored: bool = False

    def add(self, weapon: str, distance_u: float, bullets: int, killed: bool = False) -> None:
        n = min(max(bullets, 1), MAX_BULLETS) - 1
        for key in _keys(weapon, distance_u):
            self.counts.setdefault(key, [0.0] * MAX_BULLETS)[n] += 1
            self.killed.setdefault(key, [0.0] * MAX_BULLETS)[n] += killed

    def _table(self, key: str) -> tuple[np.ndarray, np.ndarray] | None:
        if key not in self.counts:
            return None
        killed = self.killed.get(key, [0.0] * MAX_BULLETS)
        return np.asarray(self.counts[key], np.float64), np.asarray(killed, np.float64)

    def probabilities(self, weapon: str, distance_u: float) -> np.ndarray:
        """(MAX_BULLETS,) P(1..MAX_BULLETS bullets); one bullet when nothing was counted."""
        tables = [t for t in map(self._table, _keys(weapon, distance_u)) if t is not None]
        if not tables or tables[0][0].sum() == 0:
            p = np.zeros(MAX_BULLETS)
            p[0] = 1.0
            return p
        if not self.censored:
            counts = tables[0][0]
            p = counts / counts.sum()
            for counts, _ in tables[1:]:
                p = (counts + PRIOR_STEPS * p) / (counts.sum() + PRIOR_STEPS)
            return p
        hazard = np.ones(MAX_BULLETS)
        for counts, killed in tables:
            at_risk = np.cumsum(counts[::-1])[::-1] - killed
            hazard = (counts - killed + PRIOR_STEPS * hazard) / (at_risk + PRIOR_STEPS)
        most = int(np.flatnonzero(tables[min(len(tables), 3) - 1][0])[-1])
        hazard[most:] = 1.0  # never more bullets than the weapon was seen to land
        alive = np.concatenate([[1.0], np.cumprod(1.0 - hazard)[:-1]])
        return alive * hazard

    def to_dict(self) -> dict[str, object]:
        return {"counts": self.counts, "killed": self.killed, "censored": self.censored}

    @classmethod
    def from_dict(cls, data: dict) -> BulletCounts:
        """Counts written by `to_dict`, or by older versions (tables "every", "by_class" and
        "by_weapon", nothing censored)."""

        def floats(table: dict) -> dict[str, list[float]]:
            return {str(k): [float(v) for v in c] for k, c in table.items()}

        if "counts" in data:
            return cls(floats(data["counts"]), floats(data["killed"]), bool(data["censored"]))
        counts = {ALL: [float(v) for v in data["every"]]}
        counts |= {f"class:{k}": c for k, c in floats(data["by_class"]).items()}
        counts |= floats(data.get("by_weapon", {}))
        return cls(counts)

    def check(self, name: str = "bullets") -> None:
        """A ValueError naming the table (`name`, as in rules.json) and its key unless every
        table holds `MAX_BULLETS` counts, each finite and not negative, and no more killed
        than counted."""
        for key, counts in self.counts.items():
            killed = self.killed.get(key, [0.0] * MAX_BULLETS)
            where = f"{name} {shortened(key)!r}"
            if len(counts) != MAX_BULLETS or len(killed) != MAX_BULLETS:
                raise ValueError(f"{where}: bullet counts must be {MAX_BULLETS} counts")
            for table in (counts, killed):
                if not all(math.isfinite(v) and v >= 0 for v in table):
                    raise ValueError(f"{where}: counts must be finite and not negative")
            if not all(k <= c for k, c in zip(killed, counts, strict=True)):
                raise ValueError(f"{where}: more steps killed than counted")
