"""Changes made to a round from outside its own rules (`OutsideChanges`, part of `Simulator`):
what a replay following the data, or a plan across a graph gap, does to the agents and the bomb;
and what any death changes in the round (`_kill`), scripted or not."""

from __future__ import annotations

import numpy as np

from decoy_cli.sim.falls import Falls
from decoy_cli.sim.movement.base import MoverBase
from decoy_cli.sim.round_state import RoundState
from decoy_cli.sim.rules import BombRules
from decoy_cli.sim.state import Agents, Bomb, RoundOutcome, SimEvent
from decoy_cli.waypoints.graph import WaypointGraph
from decoy_cli.weapons import NO_WEAPON, max_speed_m_s


class OutsideChanges:
    """The simulator's methods for changes from outside the round; the round's parts they
    change are the simulator's (`Simulator.__init__`)."""

    graph: WaypointGraph
    agents: Agents
    mover: MoverBase
    rules: BombRules
    state: RoundState
    falls: Falls
    bomb: Bomb
    events: list[SimEvent]
    tick: int
    outcome: RoundOutcome | None
    _deciding: int  # the agent whose policy is deciding right now

    def relocate(self, agent: int, node: int) -> None:
        """Put an agent on a waypoint directly (a plan across a graph gap); counted as an event.

        Inside the agent's own decision the decision that follows says what it does next;
        from anywhere else its walk or STOP ends and it is asked again at the next tick."""
        self.mover.place(agent, self.graph.positions[node])
        self.agents.position[agent] = self.graph.positions[node]
        self.agents.node[agent] = node
        self.state.goal_node[agent] = -1
        self.falls.set(agent, 0.0)
        if agent != self._deciding:
            self.mover.clear_goal(agent)
            self.state.hold_until[agent] = 0
            self.state.waiting[agent] = bool(self.agents.alive[agent])
        self.events.append(SimEvent(self.tick, "relocate", agent, data={"node": int(node)}))

    def hand_bomb(self, agent: int) -> None:
        """Give the bomb to an alive T from outside the rules (a replay following the data's
        carrier); see `BombRules.hand_over`. Nothing changes hands after the round's end."""
        if self.outcome is None:
            self.events += self.rules.hand_over(self.tick, self.agents, self.bomb, agent)

    def drop_bomb(self, position: np.ndarray) -> None:
        """The carrier lets the bomb go at `position` (a replay following the data's drop); see
        `BombRules.drop`. Nothing happens after the round's end."""
        if self.outcome is None:
            self.events += self.rules.drop(self.tick, self.agents, self.bomb, position)

    def kill(self, agent: int, reason: str) -> None:
        """Kill an agent from outside the combat step (a scripted death in a replay)."""
        if self.agents.alive[agent]:
            self.agents.alive[agent] = False
            self.agents.hp[agent] = 0
            self.events.append(SimEvent(self.tick, "death", agent, data={"reason": reason}))
            self._kill(agent)
        self.falls.set(agent, 0.0)

    def equip(
        self, agent: int, *, weapon: str | None = None, has_defuser: bool | None = None
    ) -> None:
        """Change what an agent holds from outside the round (a replay following the data): the
        weapon in hand, whose full speed then caps its moves (`MoverBase.set_max_speed`), and
        the defuse kit; None leaves either as it is."""
        if weapon is not None:
            self.agents.weapon[agent] = weapon
            self.mover.set_max_speed(agent, max_speed_m_s(str(weapon)))
        if has_defuser is not None:
            self.agents.has_defuser[agent] = has_defuser

    def disarm(self, agent: int) -> None:
        """Take the weapon out of an agent's hands (a replayed player the data shows dead, a
        target until removed): it shoots nobody. The mover's cap on it stays; a decision with no
        cap of its own takes the empty hand's speed, as any takes its weapon's."""
        self.agents.weapon[agent] = NO_WEAPON

    def _kill(self, agent: int) -> None:
        """What a death changes in the round besides the agent's health (by the combat step, a
        fall or `kill`): its body leaves the mover, it wants nothing more, and the bomb rules
        stop its plant or defuse and drop the bomb it carried."""
        self.mover.remove(agent)
        state = self.state
        state.waiting[agent] = False
        state.wants_plant[agent] = False
        state.wants_defuse[agent] = False
        if self.outcome is None:  # after the end the bomb stays as the round left it
            self.events += self.rules.on_death(self.tick, agent, self.agents, self.bomb)
