"""The durations and ranges of the bomb and round rules (`BombRules`, decoy_cli/sim/rules.py),
set in seconds and metres and held as whole tick counts, so every rule fires on an exact tick."""

from __future__ import annotations

import math
from dataclasses import dataclass, field

from decoy_cli.csgo import TICK_RATE, seconds_to_ticks


@dataclass(frozen=True)
class RulesConfig:
    """Durations (seconds) and ranges (metres) of the bomb and round rules.

    The durations are converted once to whole tick counts (`round_ticks`, `plant_ticks`,
    `bomb_ticks`, `defuse_ticks`, `defuse_kit_ticks`) by `seconds_to_ticks` (rounded up).
    """

    tick_rate: int = TICK_RATE
    round_time_s: float = 115.0
    plant_s: float = 3.0
    """CS:GO's C4 arm time; the 9 real plants with a `plant_begin` in
    ../shared/data/esta_dust2_events take 3.04 to 3.06 s from `plant_begin` to `plant`
    (benchmarks/studies/bomb_timing_study.py)."""
    bomb_timer_s: float = 40.0
    """CS:GO's C4 timer (mp_c4timer, 40 s in competitive play)."""
    defuse_s: float = 10.0
    """CS:GO's defuse time without a kit."""
    defuse_kit_s: float = 5.0
    """CS:GO's defuse time with a kit; the one real defuse in ../shared/data/esta_dust2_events
    took 5.02 s from `defuse_start` to `defuse` (benchmarks/studies/bomb_timing_study.py)."""
    defuse_range_m: float = 1.5  # horizontal; CS:GO's use range is about 62 u (1.2 m)
    defuse_vertical_m: float = 1.0
    pickup_range_m: float = 0.8  # horizontal
    pickup_vertical_m: float = 1.0
    auto_pickup: bool = True
    """A T walking over a dropped bomb picks it up (CS:GO); a replay turns it off and lets the
    data say who picks it up."""
    bomb_enabled: bool = True
    round_ticks: int = field(init=False)
    plant_ticks: int = field(init=False)
    bomb_ticks: int = field(init=False)
    defuse_ticks: int = field(init=False)
    defuse_kit_ticks: int = field(init=False)

    def __post_init__(self) -> None:
        if isinstance(self.tick_rate, bool) or not isinstance(self.tick_rate, int):
            raise ValueError(f"tick_rate must be an int, got {self.tick_rate!r}")
        positive = {
            "tick_rate": self.tick_rate,
            "round_time_s": self.round_time_s,
            "plant_s": self.plant_s,
            "bomb_timer_s": self.bomb_timer_s,
            "defuse_s": self.defuse_s,
            "defuse_kit_s": self.defuse_kit_s,
            "defuse_range_m": self.defuse_range_m,
            "defuse_vertical_m": self.defuse_vertical_m,
            "pickup_range_m": self.pickup_range_m,
            "pickup_vertical_m": self.pickup_vertical_m,
        }
        for name, value in positive.items():
            if not (math.isfinite(value) and value > 0):
                raise ValueError(f"{name} must be a positive number, got {value!r}")
        for name, seconds in (
            ("round_ticks", self.round_time_s),
            ("plant_ticks", self.plant_s),
            ("bomb_ticks", self.bomb_timer_s),
            ("defuse_ticks", self.defuse_s),
            ("defuse_kit_ticks", self.defuse_kit_s),
        ):
            object.__setattr__(self, name, seconds_to_ticks(seconds, self.tick_rate))
