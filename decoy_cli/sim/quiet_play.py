"""Quiet stretches played in compiled code: decisions and kinematic motion, event to event.

A quiet stretch is a run of ticks on which nothing but decisions and motion can happen: up to
the next combat step, recorded tick, bomb-rule tick or the end (`quiet_ticks.stretch_end`). A
policy whose choices need no Python per decision (`QuietPlayer`) plays it in one compiled loop
(`play_quiet`): at each tick the due agents decide, then the motion glides to the next arrival
or decision and a carried bomb follows its carrier, exactly as `Simulator.run` plays it tick by
tick. Choices come from either

* uniform draws over each agent's possible actions (`random_play.RandomPolicy`), or
* actions handed in for the agents due at the stretch's first tick (the environment's step,
  `env_step`), after which the loop stops before the next tick at which an agent is due.

It hands back to Python when anything else may follow: a damaging drop, the decision limit,
the stretch's end, or a STOP to plant or defuse by an agent the bomb rules watch (the carrier;
everyone once the bomb is planted). The engine takes over what the loop did
(`Simulator.note_quiet_play`), so the round is tick for tick what stepping gives. This module
knows nothing of the engine: it works on the round's arrays (`round_state`). The same
decisions (`decide_due`) serve the ticks the engine plays itself (`decide_tick`), with either
mover.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from enum import IntEnum
from typing import NamedTuple, Protocol, runtime_checkable

import numpy as np

from decoy_cli.compiled import njit_cached
from decoy_cli.sim.decisions import Decision, Taken, take_decision
from decoy_cli.sim.movement.kernels import kinematic_glide
from decoy_cli.sim.round_state import RoundState, take_motion
from decoy_cli.sim.rules import carry
from decoy_cli.sim.schedule import is_due, next_due
from decoy_cli.waypoints.graph import STOP_ACTION
from decoy_cli.weapons import max_speed_m_s


class StretchEnd(IntEnum):
    """How `play_quiet` ended."""

    QUIET_END = 0
    """It reached the stretch's end, or an agent due next was handed a move no edge makes (the
    next tick is Python's to play, which records the impossible move)."""
    NEED_DRAWS = 1
    """It has too few draws left for the agents due next."""
    DECIDED = 2
    """It made decisions after which Python goes on with the tick."""
    DUE = 3
    """An agent is due with no action handed in (the tick is not begun)."""
    AIRBORNE = 4
    """An agent asked to move is in the air."""


DRAW = -2
"""In `Choices.given`: the agent's action is drawn (-1: none handed in; 0..8: this action)."""


@runtime_checkable
class QuietPlayer(Protocol):
    """A policy whose choices need no Python per decision: `Simulator.run` plays its quiet
    stretches in compiled code (`play_stretch`) with its `Choices`."""

    def choices_for(self, n: int) -> Choices:
        """The choices of a round of `n` agents."""
        ...

    def refill(self) -> None:
        """More draws after the rest of the current ones (`StretchEnd.NEED_DRAWS`)."""
        ...


class TopSpeeds:
    """Each agent's full speed with its weapon in hand (m/s), kept while the weapons stay."""

    def __init__(self) -> None:
        self._weapons: list[str] = []
        self._top = np.zeros(0)

    def of(self, weapons: np.ndarray) -> np.ndarray:
        key = weapons.tolist()
        if key != self._weapons:
            self._weapons = key
            self._top = np.array([max_speed_m_s(str(w)) for w in key])
        return self._top


@dataclass
class Choices:
    """Where a stretch's decisions come from, per agent (N,) and for every STOP; the same
    choices decide one agent at a time on the Python path (`decision`)."""

    given: np.ndarray  # int64: an action 0..8 handed in (used once), DRAW, or -1 (stop when due)
    draws: np.ndarray  # float64 uniform draws in [0, 1), used in order from `next_draw`
    next_draw: int
    hold_ticks: int  # how long a STOP holds, at least 1 tick
    plant: np.ndarray  # bool: a STOP of this agent wants to plant
    defuse: np.ndarray  # bool: a STOP of this agent wants to defuse
    top_speeds: TopSpeeds = field(default_factory=TopSpeeds)
    _decisions: dict[tuple[bool, bool, int], Decision] = field(default_factory=dict)

    def arrays(self, top: np.ndarray) -> ChoiceArrays:
        """These choices and the agents' full speeds `top` (m/s) as compiled code takes them."""
        return self.given, self.draws, self.plant, self.defuse, top, self.hold_ticks

    def decision(self, agent: int, action: int) -> Decision:
        """The engine's `Decision` of `action` by `agent`, as `play_quiet` takes it: a move at
        full speed, or a STOP of `hold_ticks` that plants or defuses as the agent's flags say."""
        stop = action == STOP_ACTION
        key = (stop and bool(self.plant[agent]), stop and bool(self.defuse[agent]), action)
        found = self._decisions.get(key)
        if found is None:
            found = self._decisions[key] = Decision(
                action, hold_ticks=self.hold_ticks, plant=key[0], defuse=key[1]
            )
        return found


ChoiceArrays = tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray, int]
"""`Choices.arrays`: given, draws, plant, defuse, top, hold_ticks (a tuple costs numba less to
take than a struct, and the draws are replaced as they run out)."""


class Stretch(NamedTuple):
    """What `play_stretch` played, for the engine to take over (`Simulator.note_quiet_play`)."""

    tick: int  # the tick it reached
    made: int  # decisions made
    falls: int  # damaging drops started
    status: StretchEnd


def play_stretch(
    state: RoundState, tick: int, horizon: int, decisions_left: int, watch: np.ndarray,
    choices: Choices, weapons: np.ndarray, carrier: int, bomb_position: np.ndarray,
) -> Stretch:  # fmt: skip
    """Play the quiet stretch of a round with the kinematic mover after `tick` through at most
    `horizon` with `choices` (`play_quiet`) and the agents' `weapons` (their full speeds),
    making at most `decisions_left` decisions, the bomb at `bomb_position` following `carrier`
    (`BombRules.carrier`); `choices.next_draw` moves on."""
    if choices.hold_ticks < 1:
        raise ValueError(f"a STOP holds at least 1 tick, not {choices.hold_ticks}")
    c = choices.arrays(choices.top_speeds.of(weapons))
    reached, used, made, falls, status = play_quiet(
        state.kernel, c, tick, horizon, choices.next_draw, decisions_left, watch, carrier,
        bomb_position,
    )  # fmt: skip
    choices.next_draw = used
    return Stretch(reached, made, falls, StretchEnd(status))


def decide_tick(
    state: RoundState, tick: int, player: QuietPlayer, weapons: np.ndarray
) -> tuple[int, int]:
    """The decisions of the agents due at `tick` with `player`'s choices, in compiled code
    (`decide_due`), for a tick the engine plays itself; returns the decisions made and the
    change in the number of agents on a damaging drop."""
    n = len(weapons)
    choices = player.choices_for(n)
    if len(choices.draws) - choices.next_draw < n:
        player.refill()
    c = choices.arrays(choices.top_speeds.of(weapons))
    unwatched = np.zeros(n, np.bool_)  # no stretch to hand back
    used, made, falls, _, airborne = decide_due(state.kernel, c, tick, choices.next_draw, unwatched)
    choices.next_draw = used
    if airborne:
        raise ValueError("an agent due for a decision is in the air")
    return made, falls


@njit_cached
def hands_back(a, act, at, watch, plant, defuse, out_edges, edge_fall):
    """Whether agent a's decision `act` at node `at` ends a quiet stretch with its tick half
    played (`play_quiet` returns DECIDED): a STOP to plant or defuse by an agent the bomb rules
    watch (they may act on it), or a damaging drop (the engine lands it)."""
    if act == STOP_ACTION:
        return watch[a] and (plant[a] or defuse[a])
    edge = out_edges[at, act]
    return edge >= 0 and edge_fall[edge] > 0.0


@njit_cached
def decide_due(r, c, tick, next_draw, watch):
    """The decisions of the agents due at `tick` (ascending) on the round `r`
    (`RoundState.kernel`), from `c` (`Choices.arrays`: draws from `next_draw` on, which must
    last), each taken as it is made (`take_decision`). Returns (next draw, decisions made,
    change in the number of agents on a damaging drop, whether one hands back (`hands_back`),
    whether an agent asked to move is in the air, where it stops)."""
    made = falls = 0
    hand_back = False
    # the fields read per agent, taken out of the structs once
    waiting, alive, hold_until, node, first, actions = (
        r.waiting,
        r.alive,
        r.hold_until,
        r.node,
        r.first,
        r.actions,
    )
    given, draws, plant, defuse, top, hold_ticks = c
    for a in range(alive.shape[0]):
        if not is_due(a, waiting, alive, hold_until, tick):
            continue
        hold_until[a] = 0
        waiting[a] = False
        at = node[a]
        act = given[a]
        if act == DRAW:
            pick = np.int64(draws[next_draw] * (first[at + 1] - first[at]))
            act = actions[first[at] + pick]
            next_draw += 1
        else:
            given[a] = -1  # used: the agent's next turn stops a stretch
        made += 1
        stop = act == STOP_ACTION
        if hands_back(a, act, at, watch, plant, defuse, r.out_edges, r.edge_fall):
            hand_back = True
        wants_plant, wants_defuse = plant[a] and stop, defuse[a] and stop
        speed = top[a]
        taken, fell = take_decision(
            r, a, act, speed, speed, hold_ticks, wants_plant, wants_defuse, tick
        )
        falls += fell
        if taken == Taken.IN_THE_AIR:
            return next_draw, made, falls, hand_back, True
    return next_draw, made, falls, hand_back, False


@njit_cached
def play_quiet(r, c, tick, horizon, next_draw, decisions_left, watch, carrier, bomb_position):
    """The quiet stretch after `tick` through `horizon`, as `Simulator.run` plays it tick by
    tick, on the round `r` (`RoundState.kernel`): at each tick the due agents decide
    (`decide_due`, `c`: `Choices.arrays`, draws from `next_draw` on), then if the tick after
    them is quiet the motion glides to the next arrival or decision or the horizon, and the
    bomb at `bomb_position` follows `carrier` (`rules.carry`; -1: nobody carries it), all the
    bomb rules do on quiet ticks. The one driver of compiled stretches: the engine's
    (`play_stretch`) and the environment's steps (`env_step`). A handed-in action must be 0..8
    (`Choices`). Returns (tick, next draw, decisions made, damaging drops started, status)."""
    given, draws, node, out_edges = c[0], c[1], r.node, r.out_edges
    alive, waiting, hold_until = r.alive, r.waiting, r.hold_until
    n = alive.shape[0]
    made = falls = 0
    while True:
        if tick + 1 > horizon:
            return tick, next_draw, made, falls, StretchEnd.QUIET_END
        drawn = 0
        for i in range(n):
            if is_due(i, waiting, alive, hold_until, tick + 1):
                if given[i] == -1:
                    return tick, next_draw, made, falls, StretchEnd.DUE
                if given[i] == DRAW:
                    drawn += 1
                elif given[i] != STOP_ACTION and out_edges[node[i], given[i]] < 0:
                    return tick, next_draw, made, falls, StretchEnd.QUIET_END
        if drawn > draws.shape[0] - next_draw:
            return tick, next_draw, made, falls, StretchEnd.NEED_DRAWS
        tick += 1
        next_draw, now, fell, hand_back, airborne = decide_due(r, c, tick, next_draw, watch)
        made += now
        falls += fell
        if airborne:
            return tick, next_draw, made, falls, StretchEnd.AIRBORNE
        if hand_back or made >= decisions_left:
            return tick, next_draw, made, falls, StretchEnd.DECIDED
        due_at = next_due(waiting, alive, hold_until, tick - 1)
        last = min(horizon, due_at - 1)
        if due_at == tick or last < tick:
            return tick, next_draw, made, falls, StretchEnd.DECIDED
        flags = r.flags
        flags[:] = False
        ticks, _ = kinematic_glide(
            r.mpos, r.start, r.target, r.fv, r.iv, flags, r.prm, last - tick + 1
        )
        tick += ticks - 1
        take_motion(r)
        carry(bomb_position, r.position, carrier)
