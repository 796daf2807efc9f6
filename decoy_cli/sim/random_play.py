"""Random valid actions: the protocol of the DECOY paper's Table 1, and a baseline opponent.

`RandomPolicy` picks a uniformly random possible action (`WaypointGraph.allowed_actions`) for
each agent asked; a STOP holds `hold_ticks` and, if told, plants or defuses (the bomb rules
let only a T carrier plant and a CT defuse). The engine makes its decisions in compiled code
(`quiet_play.QuietPlayer`), with the kinematic mover whole quiet stretches of them; its draws
come from the generator in blocks, used in the same order by `decide` (one agent at a time in
Python, the reference the tests compare with), so the round is the same either way.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from decoy_cli.sim.decisions import Decision
from decoy_cli.sim.quiet_play import DRAW, Choices

if TYPE_CHECKING:
    from decoy_cli.sim.engine import Simulator


class RandomPolicy:
    """A uniformly random possible action per decision (module docstring)."""

    BLOCK = 4096

    def __init__(
        self, rng: np.random.Generator, *, hold_ticks: int = 30, plant: bool = True,
        defuse: bool = False,
    ) -> None:  # fmt: skip
        self.rng = rng
        self.plant = plant
        self.defuse = defuse
        self._choices = Choices(
            np.zeros(0, np.int64), np.zeros(0), 0, max(1, int(hold_ticks)), np.zeros(0, bool),
            np.zeros(0, bool),
        )  # fmt: skip

    def decide(self, sim: Simulator, agent: int) -> Decision:
        first, actions = sim.graph.allowed_actions
        node = int(sim.agents.node[agent])
        choices = self.choices_for(sim.agents.count)
        if choices.next_draw == len(choices.draws):
            self.refill()
        count = int(first[node + 1] - first[node])
        pick = int(choices.draws[choices.next_draw] * count)
        choices.next_draw += 1
        return choices.decision(agent, int(actions[first[node] + pick]))

    def choices_for(self, n: int) -> Choices:
        """The choices for `n` agents: every action drawn, every STOP alike."""
        choices = self._choices
        if len(choices.given) != n:
            choices.given = np.full(n, DRAW, np.int64)
            choices.plant = np.full(n, self.plant)
            choices.defuse = np.full(n, self.defuse)
        return choices

    def refill(self) -> None:
        """A new block after what is left of the current one."""
        choices = self._choices
        rest = choices.draws[choices.next_draw :]
        choices.draws = np.concatenate([rest, self.rng.random(self.BLOCK)])
        choices.next_draw = 0
