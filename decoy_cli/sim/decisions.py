"""What an agent decides when it is asked: `Decision` (the engine's `Policy` returns one)."""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class Decision:
    """What an agent does next: a compass move (0..7) at a speed, or STOP for `hold_ticks`.

    `speed` is m/s, capped by `max_speed` (None: the weapon's CS:GO maximum); None = full speed.
    A replay may raise the cap above the weapon's where the data shows the player moving faster
    (strafe-jumps, falls). `plant` and `defuse` say whether the agent wants to plant or defuse
    while it stands still.
    """

    action: int
    speed: float | None = None
    max_speed: float | None = None
    hold_ticks: int = 30
    plant: bool = False
    defuse: bool = False
