"""When and by whom players died, in the data and in a replay: what the kill-level fidelity
(`decoy_cli.metrics.kills`) compares.

The data's death time is the tick of the player's kill event when the data has one between the
player's last frame alive and the first frame showing it dead (frames at 1 or 2 per second
place a death only to the frame), else that first dead frame's time. The replay's is the tick
of its kill or death event.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

import numpy as np

from decoy_cli.csgo import TICK_RATE
from decoy_cli.esta import Round
from decoy_cli.replay.plans import PlayerPlan
from decoy_cli.sim.state import SimEvent

DeathProtocol = Literal["simulated", "data"]
"""Who decides deaths with shooting on: the simulated fight, or the data (the paper's protocol:
a player dies when the data says so; shooting still wounds but does not kill)."""
DEATH_PROTOCOLS: tuple[DeathProtocol, ...] = ("simulated", "data")


@dataclass(frozen=True)
class RoundDeaths:
    """Per player (rows of the round): death time in seconds (NaN: survived), the killer's
    row (-1: none known, or no kill) and whether the fight caused the death (a kill or a fall,
    not a death scripted from the data)."""

    seconds: np.ndarray
    killer: np.ndarray
    by_fight: np.ndarray


def data_deaths(round_: Round, plans: list[PlayerPlan]) -> RoundDeaths:
    """The data's deaths (module docstring)."""
    count = len(plans)
    seconds = np.array([plan.death_seconds for plan in plans], dtype=np.float64)
    killer = np.full(count, -1, dtype=np.int64)
    by_fight = np.isfinite(seconds)
    rows = {player.name: p for p, player in enumerate(round_.players)}
    kills = round_.kills
    if not len(kills) or not {"victimName", "attackerName", "seconds"} <= set(kills.columns):
        return RoundDeaths(seconds, killer, by_fight)
    frame_seconds = np.asarray(round_.frame_seconds, dtype=np.float64)
    for kill in kills.sort_values("seconds", kind="stable").itertuples():
        victim = rows.get(kill.victimName, -1) if isinstance(kill.victimName, str) else -1
        if victim < 0 or plans[victim].death_frame < 0 or not np.isfinite(kill.seconds):
            continue
        dead_from = plans[victim].death_frame
        alive_until = frame_seconds[dead_from - 1] if dead_from > 0 else -np.inf
        if alive_until - 1e-6 <= kill.seconds <= frame_seconds[dead_from] + 1e-6:
            seconds[victim] = float(kill.seconds)
            name = kill.attackerName
            killer[victim] = rows.get(name, -1) if isinstance(name, str) else -1
    return RoundDeaths(seconds, killer, by_fight)


def replay_deaths(events: list[SimEvent], count: int) -> RoundDeaths:
    """The replay's deaths from its events: a "kill" (the killer credited) or a "death" (a
    fall, by the fight; or scripted from the data: not)."""
    seconds = np.full(count, np.nan)
    killer = np.full(count, -1, dtype=np.int64)
    by_fight = np.zeros(count, dtype=bool)
    for event in events:
        if event.kind in ("kill", "death"):
            victim = event.other if event.kind == "kill" else event.agent
            if victim is not None and victim >= 0 and np.isnan(seconds[victim]):
                seconds[victim] = event.tick / TICK_RATE
                killer[victim] = event.agent if event.kind == "kill" else -1
                by_fight[victim] = event.data.get("reason") != "scripted"
    return RoundDeaths(seconds, killer, by_fight)
