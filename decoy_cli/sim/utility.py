"""Smokes, fires and flashes as the fight sees them: the data's utility on the simulator's clock.

No agent throws anything: the utility is the data's (a replay's round, `Utility` built by the
replay), each with its real window. Three rules, from the game:

* A smoke blocks sight through its cloud: the line between two eyes is blocked when either eye
  is inside a cloud, or when the lengths of the line inside clouds add up to more than 70% of a
  cloud's radius (CS:GO's server-side test, `LineGoesThroughSmoke`: a sphere of 166 u centred
  60 u above the detonation; CS2 fills its volume in voxels around walls, for which the sphere
  stands in). The cloud blocks at once on detonation, as the game's test does.
* A fire burns a player whose feet are within 150 u of its centre horizontally (the game's
  `inferno_max_range`, the farthest its flames spread) and within a standing player's height of
  it vertically, at 40 HP a second (measured: the real events' fire damage comes every 0.203 s
  at most 8 HP, og-navi-blast2020 and de_ancient; `benchmarks/studies/utility_constants.py`).
  Fire does not block sight.
* A flashed player does not shoot while blind: from the blind's tick for its duration (awpy's
  blinds, in seconds).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from decoy_cli.csgo import HAMMER_TO_M, PLAYER_HEIGHT_M

SMOKE_RADIUS_M = 166 * HAMMER_TO_M
"""The smoke's sphere for sight: CS:GO's `CONSTANT_UNITS_SMOKEGRENADERADIUS`, 166 u."""
SMOKE_CENTRE_UP_M = 60 * HAMMER_TO_M
"""The sphere's centre above the detonation: 60 u (`CheckTotalSmokedLength`)."""
SMOKE_BLOCKS_M = 0.7 * SMOKE_RADIUS_M
"""Sight through smoke longer than this is blocked (the game's 70% of the radius)."""
SMOKE_INSIDE = (0.95, 1.0)
"""An eye closer to the centre than these shares of the radius (looker, seen) is inside."""
FIRE_RADIUS_M = 150 * HAMMER_TO_M
"""The farthest a fire's flames spread from its centre: the game's `inferno_max_range`, 150 u."""
FIRE_HP_PER_S = 40.0
"""HP a second a fire takes from a player in it (measured, module docstring)."""


def _empty(shape: tuple[int, ...], dtype: type) -> np.ndarray:
    return np.zeros(shape, dtype=dtype)


@dataclass(frozen=True, eq=False)
class Utility:
    """A round's smokes, fires and blinds on the simulator's clock (ticks).

    Smokes and fires: centre (K, 3) metres (the detonation; the smoke's sphere sits above it)
    and the ticks [start, end) they are active; blinds: the agent and its ticks [start, end).
    """

    smoke_at: np.ndarray = field(default_factory=lambda: _empty((0, 3), float))
    smoke_start: np.ndarray = field(default_factory=lambda: _empty((0,), int))
    smoke_end: np.ndarray = field(default_factory=lambda: _empty((0,), int))
    fire_at: np.ndarray = field(default_factory=lambda: _empty((0, 3), float))
    fire_start: np.ndarray = field(default_factory=lambda: _empty((0,), int))
    fire_end: np.ndarray = field(default_factory=lambda: _empty((0,), int))
    blind_agent: np.ndarray = field(default_factory=lambda: _empty((0,), int))
    blind_start: np.ndarray = field(default_factory=lambda: _empty((0,), int))
    blind_end: np.ndarray = field(default_factory=lambda: _empty((0,), int))

    @property
    def counts(self) -> dict[str, int]:
        """How many smokes, fires and blinds the round holds."""
        return {
            "smokes": len(self.smoke_start),
            "fires": len(self.fire_start),
            "blinds": len(self.blind_start),
        }

    def sight_blocked(self, eyes_from: np.ndarray, eyes_to: np.ndarray, tick: int) -> np.ndarray:
        """(K,) whether smoke active at `tick` blocks each line from `eyes_from` to `eyes_to`
        (K, 3 metres; module docstring)."""
        blocked = np.zeros(len(eyes_from), dtype=bool)
        active = (self.smoke_start <= tick) & (tick < self.smoke_end)
        if not active.any() or not len(eyes_from):
            return blocked
        centres = self.smoke_at[active] + np.array([0.0, 0.0, SMOKE_CENTRE_UP_M])
        radius = SMOKE_RADIUS_M
        line = eyes_to - eyes_from  # (K, 3)
        length = np.linalg.norm(line, axis=1)
        unit = line / np.where(length > 0, length, 1.0)[:, None]
        smoked = np.zeros(len(eyes_from))
        for centre in centres:
            inside_from = np.linalg.norm(eyes_from - centre, axis=1) < SMOKE_INSIDE[0] * radius
            inside_to = np.linalg.norm(eyes_to - centre, axis=1) < SMOKE_INSIDE[1] * radius
            blocked |= inside_from | inside_to
            along = np.clip(np.einsum("kd,kd->k", centre - eyes_from, unit), 0.0, length)
            closest = eyes_from + unit * along[:, None]
            gap_sq = np.sum((closest - centre) ** 2, axis=1)
            chord = 2.0 * np.sqrt(np.maximum(radius**2 - gap_sq, 0.0))
            smoked += np.where(gap_sq < radius**2, chord, 0.0)
        return blocked | (smoked > SMOKE_BLOCKS_M)

    def blinded(self, count: int, tick: int) -> np.ndarray:
        """(count,) whether each agent is blind at `tick`."""
        out = np.zeros(count, dtype=bool)
        active = (self.blind_start <= tick) & (tick < self.blind_end)
        out[self.blind_agent[active]] = True
        return out

    def burning(self, feet: np.ndarray, tick: int) -> np.ndarray:
        """(N,) whether each agent's feet (N, 3 metres) stand in a fire active at `tick`."""
        out = np.zeros(len(feet), dtype=bool)
        active = (self.fire_start <= tick) & (tick < self.fire_end)
        for centre in self.fire_at[active]:
            flat = np.hypot(feet[:, 0] - centre[0], feet[:, 1] - centre[1])
            out |= (flat <= FIRE_RADIUS_M) & (np.abs(feet[:, 2] - centre[2]) <= PLAYER_HEIGHT_M)
        return out
