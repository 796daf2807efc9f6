"""Random valid actions: a policy that asks the engine nothing per decision in quiet stretches.

`RandomPolicy` picks a uniformly random possible action (`WaypointGraph.allowed_actions`) for
each agent asked; a STOP holds `hold_ticks` and, if told, plants (T) or defuses (CT). It is the
protocol of the DECOY paper's Table 1, and a baseline opponent.

With the kinematic mover, the engine hands it whole quiet stretches (`Simulator.run`): ticks on
which nothing but decisions and motion can happen, up to the next combat step, recorded tick,
bomb-rule tick or the end. `play_quiet` then makes the decisions and crosses the motion between
them in one compiled loop (`_play`), jumping from arrival to arrival, and hands back to Python
when anything else may follow: a damaging drop, the decision limit, the stretch's end, or a
STOP to plant or defuse by an agent the bomb rules watch (the carrier; everyone once the bomb
is planted). Decisions come from the same uniform draws in the same order as deciding one agent
at a time, so the round is tick for tick the same either way.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np
from numba import njit

from decoy_cli.sim.decisions import Decision
from decoy_cli.sim.movement import KinematicMover
from decoy_cli.sim.movement.kernels import begin_edge, kinematic_glide, stand_still
from decoy_cli.sim.movement.layout import F_HEADING, R_ARRIVED, R_MOVED
from decoy_cli.sim.schedule import next_due, note_arrivals
from decoy_cli.waypoints.graph import STOP_ACTION
from decoy_cli.weapons import max_speed_m_s

if TYPE_CHECKING:
    from decoy_cli.sim.engine import Simulator

QUIET_END, NEED_DRAWS, DECIDED, AIRBORNE = range(4)
"""How `_play` ended: it reached the stretch's end (the next tick is Python's to play); it has
too few draws left for the agents due next; it made decisions after which Python goes on with
the tick; an agent asked to move is in the air."""


class RandomPolicy:
    """A uniformly random possible action per decision (module docstring).

    The draws come from the generator in blocks of `BLOCK`, used in order, so deciding one agent
    at a time (`decide`) and in compiled stretches (`play_quiet`) give the same decisions.
    """

    BLOCK = 4096

    def __init__(
        self, rng: np.random.Generator, *, hold_ticks: int = 30, plant: bool = True,
        defuse: bool = False,
    ) -> None:  # fmt: skip
        self.rng = rng
        self.hold_ticks = max(1, int(hold_ticks))
        self.plant = plant
        self.defuse = defuse
        self._draws = np.zeros(0)
        self._next = 0
        self._weapons: tuple[str, ...] = ()  # the agents' weapons and their top speeds, m/s
        self._top = np.zeros(0)
        self._decisions = [
            Decision(a, hold_ticks=self.hold_ticks, plant=plant and a == STOP_ACTION,
                     defuse=defuse and a == STOP_ACTION)
            for a in range(STOP_ACTION + 1)
        ]  # fmt: skip

    def decide(self, sim: Simulator, agent: int) -> Decision:
        first, actions = sim.graph.allowed_actions
        node = int(sim.agents.node[agent])
        if self._next == len(self._draws):
            self._refill()
        count = int(first[node + 1] - first[node])
        pick = int(self._draws[self._next] * count)
        self._next += 1
        return self._decisions[int(actions[first[node] + pick])]

    def play_quiet(
        self, sim: Simulator, horizon: int, max_decisions: int, watch: np.ndarray
    ) -> int:
        """Play from `sim.tick` through the quiet stretch ending at `horizon` (`_play`); returns
        how it ended, with the engine's state where the per-tick loop would have it."""
        while True:
            status = self._play_once(sim, horizon, max_decisions, watch)
            if status != NEED_DRAWS:
                return status
            self._refill()

    def _refill(self) -> None:
        """A new block after what is left of the current one."""
        self._draws = np.concatenate([self._draws[self._next :], self.rng.random(self.BLOCK)])
        self._next = 0

    def _play_once(
        self, sim: Simulator, horizon: int, max_decisions: int, watch: np.ndarray
    ) -> int:
        graph, agents, mover = sim.graph, sim.agents, sim.mover
        if not isinstance(mover, KinematicMover):
            raise TypeError("compiled stretches need the kinematic mover")
        first, actions = graph.allowed_actions
        pos, start, target, fv, iv, flags, params = mover.kernel_arrays()
        weapons = tuple(agents.weapon)
        if weapons != self._weapons:
            self._weapons = weapons
            self._top = np.array([max_speed_m_s(str(w)) for w in weapons])
        tick, used, made, falls, glide_end, status = _play(
            sim.tick, horizon, self._draws, self._next, first, actions, self.hold_ticks,
            self.plant, self.defuse, max_decisions - sim.decision_count, watch, self._top,
            graph.out_edges, graph.edge_target, graph.edge_kind, graph.fall_m, graph.positions,
            agents.node, agents.alive, agents.yaw, sim.waiting, sim.hold_until, sim.decisions,
            sim.wants_plant, sim.wants_defuse, sim.goal_node, sim.fall_m,
            pos, start, target, fv, iv, flags, params, mover.jump_speed, mover.gravity,
        )  # fmt: skip
        self._next = used
        sim.note_quiet_play(tick, made, falls, glide_end >= 0)
        if status == AIRBORNE:
            raise ValueError("an agent due for a decision is in the air")
        return status


@njit(cache=True)
def _play(
    tick, horizon, draws, next_draw, first, actions, hold_ticks, plant, defuse, decisions_left,
    watch, top, out_edges, edge_target, edge_kind, edge_fall, positions,
    node, alive, yaw, waiting, hold_until, decisions, wants_plant, wants_defuse, goal_node, fall_m,
    pos, start, target, fv, iv, flags, prm, jump_speed, gravity,
):  # fmt: skip
    """The quiet stretch after `tick` through `horizon`, as `Simulator.run` plays it tick by
    tick: at each tick the due agents (ascending) decide, then if the tick after them is quiet
    the motion glides to the next arrival or decision or the horizon. Returns (tick, next draw,
    decisions made, damaging drops started, tick of the last glide's end or -1, status)."""
    n = alive.shape[0]
    made = falls = 0
    glide_end = -1
    one = np.empty(1, np.int64)
    while True:
        if tick + 1 > horizon:
            return tick, next_draw, made, falls, glide_end, QUIET_END
        due = 0
        for i in range(n):
            if alive[i] and (waiting[i] or (hold_until[i] > 0 and tick + 1 >= hold_until[i])):
                due += 1
        if due > draws.shape[0] - next_draw:
            return tick, next_draw, made, falls, glide_end, NEED_DRAWS
        tick += 1
        hand_back = False
        for a in range(n):
            if not (alive[a] and (waiting[a] or (hold_until[a] > 0 and tick >= hold_until[a]))):
                continue
            hold_until[a] = 0
            waiting[a] = False
            at = node[a]
            act = actions[first[at] + np.int64(draws[next_draw] * (first[at + 1] - first[at]))]
            next_draw += 1
            decisions[a] += 1
            made += 1
            stop = act == STOP_ACTION
            wants_plant[a] = plant and stop
            wants_defuse[a] = defuse and stop
            if watch[a] and stop and (plant or defuse):  # the bomb rules may act on it
                hand_back = True
            if stop:
                one[0] = a
                stand_still(one, fv, iv)
                hold_until[a] = tick + hold_ticks
                continue
            edge = out_edges[at, act]
            goal = edge_target[edge]
            goal_node[a] = goal
            if edge_fall[edge] > 0.0:
                fall_m[a] = edge_fall[edge]
                falls += 1
                hand_back = True
            if not begin_edge(
                a, positions[goal, 0], positions[goal, 1], positions[goal, 2], edge_kind[edge],
                top[a], top[a], jump_speed, gravity, pos, target, fv, iv,
            ):  # fmt: skip
                return tick, next_draw, made, falls, glide_end, AIRBORNE
        if hand_back or made >= decisions_left:
            return tick, next_draw, made, falls, glide_end, DECIDED
        due_at = next_due(waiting, alive, hold_until, tick - 1)
        last = min(horizon, due_at - 1)
        if due_at == tick or last < tick:
            return tick, next_draw, made, falls, glide_end, DECIDED
        flags[:] = False
        ticks, _ = kinematic_glide(pos, start, target, fv, iv, flags, prm, last - tick + 1)
        tick += ticks - 1
        glide_end = tick
        for i in range(n):
            if flags[R_MOVED, i]:
                yaw[i] = fv[i, F_HEADING]
        note_arrivals(flags[R_ARRIVED], alive, node, goal_node, waiting)
