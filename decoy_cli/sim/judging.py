"""Judging a round's outcome: the rule is the rules' (`BombRules.outcome`); `OutcomeJudge` asks
it only when something it depends on changed, as the engine judges after every played tick."""

from __future__ import annotations

import numpy as np

from decoy_cli.sim.rules import BombRules
from decoy_cli.sim.state import Agents, Bomb, BombStatus, RoundOutcome


class OutcomeJudge:
    """The outcome depends only on who is alive, the bomb's status and whether the round clock
    has run out, so the rules are asked only when one of these changed since the last
    judgement."""

    def __init__(self, rules: BombRules) -> None:
        self.rules = rules
        self._alive_judged = b""  # who was alive (as bytes) when the outcome was judged
        self._judged_as: tuple[BombStatus, bool] | None = None  # and the bomb and the clock

    def judge(self, tick: int, agents: Agents, bomb: Bomb) -> RoundOutcome | None:
        """The outcome at `tick` of a round that has none yet (None: it goes on)."""
        clock_out = tick >= self.rules.config.round_ticks
        alive = agents.alive.tobytes()
        if alive == self._alive_judged and self._judged_as == (bomb.status, clock_out):
            return None
        outcome = self.rules.outcome(tick, agents, bomb)
        self._alive_judged = alive
        self._judged_as = (bomb.status, clock_out)
        return outcome

    def judged(self, alive: np.ndarray) -> bool:
        """Whether the last judgement saw these agents `alive` (not after a kill from outside)."""
        return alive.tobytes() == self._alive_judged
