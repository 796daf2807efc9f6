"""Damaging drops: which agents are on one (`RoundState.fall_m`, the drop's depth) and what the
landing costs them (`csgo.fall_damage`). The engine notes the drops its decisions start and takes
the landings its mover reports (`Simulator._moved`)."""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from decoy_cli.csgo import fall_damage
from decoy_cli.sim.round_state import RoundState
from decoy_cli.sim.state import Agents, SimEvent


class Falls:
    """The round's damaging drops. `kills` False: a fall stops at 1 HP (deaths come from
    elsewhere, as in a replay following the data)."""

    def __init__(self, state: RoundState, kills: bool) -> None:
        self.state = state
        self.kills = kills
        self.count = 0  # how many agents are on a damaging drop (`state.fall_m` > 0)
        self.killed = False  # a landing killed since the outcome was last judged

    def set(self, agent: int, depth: float) -> None:
        """Note the depth of the damaging drop an agent is on (0: none), keeping the count."""
        fall_m = self.state.fall_m
        self.count += int(depth > 0) - int(fall_m[agent] > 0)
        fall_m[agent] = depth

    def land(
        self,
        arrived: np.ndarray,
        tick: int,
        agents: Agents,
        events: list[SimEvent],
        round_over: bool,
        kill: Callable[[int, str], None],
    ) -> None:
        """Fall damage for the agents that `arrived` at the end of a drop deeper than the safe
        fall, noted in `events`; a fall that takes the last health kills (`kill`), unless nothing
        in the simulation kills (`kills`), where it leaves 1 HP. Before the round's end only
        (`round_over`): afterwards nothing changes health."""
        for agent in np.flatnonzero(arrived).tolist():
            height = float(self.state.fall_m[agent])
            if not height:
                continue
            self.set(agent, 0.0)
            damage = fall_damage(height)
            if round_over or not damage or not agents.alive[agent]:
                continue
            left = max(0 if self.kills else 1, int(agents.hp[agent]) - damage)
            agents.hp[agent] = left
            data = {"damage": damage, "height_m": round(height, 3)}
            events.append(SimEvent(tick, "fall_damage", agent, data=data))
            if left == 0:
                kill(agent, "fall")
                self.killed = True
