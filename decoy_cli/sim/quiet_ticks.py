"""Quiet ticks: the ticks of a round on which nothing but decisions and motion can happen, which
the engine crosses in one go (`Simulator.run`, its glides) or hands to compiled code with a
`quiet_play.QuietPlayer` (`play_stretches`). Asking how far they reach (`stretch_end`,
`quiet_until`) is what makes crossing them tick for tick what stepping every tick gives."""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from decoy_cli.sim.quiet_play import QuietPlayer, StretchEnd, play_stretch

if TYPE_CHECKING:
    from decoy_cli.sim.engine import Simulator


def stretch_end(sim: Simulator, tick: int, end: int) -> int:
    """The last tick, at most `end`, through which nothing but decisions and motion can
    happen after `tick`: no combat step, no recorded tick, the bomb rules have nothing to
    do and the outcome cannot change (the clock, the detonation), as long as no agent the
    rules watch decides (`BombRules.watched`); `tick` when the tick after it is not quiet."""
    alive = sim.agents.alive
    if sim.outcome is not None or not sim.judge.judged(alive):
        return tick  # judged yet? (not after a kill from outside)
    state = sim.state
    rules = sim.rules.quiet_until(
        tick, sim.agents, sim.bomb, state.wants_plant, state.wants_defuse,
        sim.mover.is_standing,
    )  # fmt: skip
    last = min(end, sim._max_tick - 1, rules)
    if sim.combat is not None:
        last = min(last, (tick // sim.combat_every_ticks + 1) * sim.combat_every_ticks - 1)
    last = min(last, sim.recorder.next_tick - 1)
    return max(tick, last)


def quiet_until(sim: Simulator, tick: int) -> int:
    """The last tick through which nothing but motion can happen after `tick`, if no agent
    arrives before: no decision falls due, and `stretch_end`. Equal to `tick` when the
    tick after it is not quiet. Asked once the decisions of the tick after `tick` are made
    (they are the only part of that tick already played)."""
    due = sim.state.next_due(tick)
    if due == tick + 1:
        return tick
    return max(tick, min(stretch_end(sim, tick, sim._max_tick), due - 1))


def play_stretches(
    sim: Simulator, player: QuietPlayer, horizon: int, limit: int, watched: np.ndarray
) -> StretchEnd:
    """Play from the round's tick through at most `horizon` with `player`'s choices in compiled
    code (`quiet_play.play_stretch`), up to `limit` decisions in all, refilling its draws
    as it needs them; the round takes over what it played (`Simulator.note_quiet_play`).
    Returns how the stretch ended."""
    choices = player.choices_for(sim.agents.count)
    while True:
        left = limit - sim.decision_count
        played = play_stretch(
            sim.state, sim.tick, horizon, left, watched, choices, sim.agents.weapon,
            sim.rules.carrier(sim.bomb), sim.bomb.position,
        )  # fmt: skip
        sim.note_quiet_play(played.tick, played.made, played.falls)
        if played.status != StretchEnd.NEED_DRAWS:
            break
        player.refill()
    if played.status == StretchEnd.AIRBORNE:
        raise ValueError("an agent due for a decision is in the air")
    return played.status
