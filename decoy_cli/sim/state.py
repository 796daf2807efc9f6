"""The simulator's round state: agents as arrays, the bomb, events and the outcome.

Agents are a struct of arrays (one row per agent) so that movement, line of sight and the damage
models work on whole batches. Everything is in metres and seconds, Source axes; `tick` counts
physics ticks at `decoy_cli.csgo.TICK_RATE` since the round started.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from enum import IntEnum
from typing import Any

import numpy as np

SIDES = ("T", "CT")


@dataclass
class Agents:
    """N agents; every array has N rows. `node` is the waypoint an agent last reached."""

    names: list[str]
    side: np.ndarray  # (N,) str, "T" or "CT"
    position: np.ndarray  # (N, 3) float64, feet, metres
    yaw: np.ndarray  # (N,) float64, degrees, 0 = +x, counter-clockwise
    hp: np.ndarray  # (N,) int16, 0..100
    armor: np.ndarray  # (N,) int16, 0..100
    helmet: np.ndarray  # (N,) bool
    has_defuser: np.ndarray  # (N,) bool
    weapon: np.ndarray  # (N,) str, awpy display names ("" = none)
    alive: np.ndarray  # (N,) bool
    node: np.ndarray  # (N,) int64

    @classmethod
    def create(
        cls,
        names: list[str],
        sides: list[str],
        positions: np.ndarray,
        nodes: np.ndarray,
        weapons: list[str] | None = None,
        hp: np.ndarray | None = None,
        armor: np.ndarray | None = None,
        helmet: np.ndarray | None = None,
        has_defuser: np.ndarray | None = None,
        yaw: np.ndarray | None = None,
    ) -> Agents:
        """Agents with CS:GO defaults: 100 HP, no armor, knife, facing east."""
        n = len(names)
        if len(sides) != n or any(s not in SIDES for s in sides):
            raise ValueError("every agent needs a side, 'T' or 'CT'")
        given = {"nodes": nodes, "weapons": weapons, "hp": hp, "armor": armor}
        given |= {"helmet": helmet, "has_defuser": has_defuser, "yaw": yaw}
        for name, values in given.items():
            if values is not None and len(values) != n:
                raise ValueError(f"{len(values)} {name} for {n} agents")
        return cls(
            names=list(names),
            side=np.asarray(sides, dtype="<U2"),
            position=np.asarray(positions, dtype=np.float64).reshape(n, 3).copy(),
            yaw=np.zeros(n) if yaw is None else np.asarray(yaw, dtype=np.float64).copy(),
            hp=np.full(n, 100, np.int16) if hp is None else np.asarray(hp, np.int16).copy(),
            armor=np.zeros(n, np.int16) if armor is None else np.asarray(armor, np.int16).copy(),
            helmet=np.zeros(n, bool) if helmet is None else np.asarray(helmet, bool).copy(),
            has_defuser=np.zeros(n, bool)
            if has_defuser is None
            else np.asarray(has_defuser, bool).copy(),
            weapon=np.asarray(weapons if weapons is not None else ["Knife"] * n, dtype=object),
            alive=np.ones(n, dtype=bool),
            node=np.asarray(nodes, dtype=np.int64).copy(),
        )

    @property
    def count(self) -> int:
        return len(self.names)

    def alive_of_side(self, side: str) -> int:
        return int(np.sum(self.alive & (self.side == side)))


class BombStatus(IntEnum):
    """Where the bomb is in its life."""

    CARRIED = 0
    DROPPED = 1
    PLANTED = 2
    DEFUSED = 3
    EXPLODED = 4


@dataclass
class Bomb:
    """The C4: who carries it or where it lies, and the progress of a plant or a defuse."""

    status: BombStatus = BombStatus.CARRIED
    carrier: int = -1  # agent index while CARRIED (-1: no bomb in this round)
    position: np.ndarray = field(default_factory=lambda: np.full(3, np.nan))
    site: str = ""  # "A" or "B" once planted
    planter: int = -1  # agent planting now (-1: none)
    plant_ticks: int = 0  # ticks of the plant in progress
    planted_tick: int = -1
    defuser: int = -1  # agent defusing now (-1: none)
    defuse_ticks: int = 0  # ticks of the defuse in progress


@dataclass(frozen=True)
class SimEvent:
    """Something that happened at a tick: plant, defuse, damage, kill, stuck, round end, ..."""

    tick: int
    kind: str
    agent: int = -1
    other: int = -1
    data: dict[str, Any] = field(default_factory=dict)


@dataclass(frozen=True)
class RoundOutcome:
    """How a round ended: the winning side and the reason, named as in ESTA/awpy."""

    winner: str
    reason: str
    tick: int
