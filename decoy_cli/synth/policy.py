"""The policy of a scripted round: routes, the bomb and the defuse, decided on demand.

`ScriptedPolicy` drives the agents of a `RoutePlan` (decoy_cli/synth/routes.py) through the
engine's on-demand decisions: each agent follows its legs along shortest paths, holds in
half-second STOPs (so it reacts to the bomb within 0.5 s), and the round's objectives take over
when they arise:

* the T carrying the bomb plants on its plant waypoint (STOP with `plant`); a T that picks up a
  dropped bomb heads for that waypoint too;
* when the bomb lies dropped, the alive T nearest it walks to it (the rules hand it over within
  0.8 m);
* when the first T reaches the attacked site, the CTs that defend elsewhere rotate to its edge
  (the plan's rotation legs);
* once the bomb is planted every alive CT walks to it; in range, a CT defuses when no alive T is
  within `DEFUSE_CLEAR_M` of the bomb, else it holds there facing the nearest T.
"""

from __future__ import annotations

import numpy as np

from decoy_cli.geometry import facing_yaw
from decoy_cli.sim.engine import Decision, Simulator
from decoy_cli.sim.state import BombStatus
from decoy_cli.synth.routes import SITE_PLACES, Leg, Places, RoutePlan
from decoy_cli.waypoints.graph import STOP_ACTION, WaypointGraph

HOLD_TICKS = 30
"""Longest STOP the policy gives: agents look at the round again every 0.5 s."""

DEFUSE_CLEAR_M = 10.0
"""A CT starts a defuse only when no alive T stands within this distance of the bomb."""


class ScriptedPolicy:
    """The engine policy of a scripted round (see the module docstring)."""

    def __init__(self, graph: WaypointGraph, places: Places, plan: RoutePlan) -> None:
        self.graph = graph
        self.places = places
        self.plan = plan
        n = len(plan.routes)
        self.legs: list[list[Leg]] = [list(route) for route in plan.routes]
        self.leg = np.zeros(n, dtype=np.int64)
        self.hold_until = np.full(n, -1, dtype=np.int64)  # -1: not yet arrived at the leg
        self.routed_to_plant = {plan.carrier}
        self.rotated: set[int] = set()
        self._on_site = np.zeros(graph.num_nodes, dtype=bool)
        self._on_site[places.nodes(SITE_PLACES[plan.site])] = True
        self._paths: dict[int, tuple[int, list[int]]] = {}
        self._bomb_node: tuple[tuple[float, ...], int] | None = None

    def decide(self, sim: Simulator, agent: int) -> Decision:
        if sim.agents.side[agent] == "T":
            return self._t_decision(sim, agent)
        return self._ct_decision(sim, agent)

    # ---- sides --------------------------------------------------------------------------------

    def _t_decision(self, sim: Simulator, agent: int) -> Decision:
        bomb = sim.bomb
        node = int(sim.agents.node[agent])
        if bomb.status == BombStatus.CARRIED and bomb.carrier == agent:
            if agent not in self.routed_to_plant:  # picked up a dropped bomb: go and plant
                self.routed_to_plant.add(agent)
                self.legs[agent] = [Leg(self.plan.plant_node)]
                self.leg[agent] = 0
                self.hold_until[agent] = -1
            if node == self.plan.plant_node:
                return Decision(STOP_ACTION, hold_ticks=HOLD_TICKS, plant=True)
        elif bomb.status == BombStatus.DROPPED and agent == self._fetcher(sim):
            target = self._node_at(bomb.position)
            if node != target:
                return self._move(agent, node, target)
            return Decision(STOP_ACTION, hold_ticks=HOLD_TICKS)
        return self._follow_legs(sim, agent, node)

    def _ct_decision(self, sim: Simulator, agent: int) -> Decision:
        bomb = sim.bomb
        if bomb.status != BombStatus.PLANTED:
            rotation = self.plan.rotations.get(agent)
            if rotation is not None and agent not in self.rotated and self._site_hit(sim):
                self.rotated.add(agent)
                self.legs[agent] = [rotation]
                self.leg[agent] = 0
                self.hold_until[agent] = -1
            return self._follow_legs(sim, agent, int(sim.agents.node[agent]))
        node = int(sim.agents.node[agent])
        target = self._node_at(bomb.position)
        agents = sim.agents
        cfg = sim.rules.config
        offset = agents.position[agent] - bomb.position
        in_range = (
            np.hypot(offset[0], offset[1]) <= cfg.defuse_range_m
            and abs(offset[2]) <= cfg.defuse_vertical_m
        )
        if not in_range:
            return self._move(agent, node, target) if node != target else self._hold()
        enemies = np.flatnonzero(agents.alive & (agents.side == "T"))
        distance = np.linalg.norm(agents.position[enemies] - bomb.position, axis=1)
        if not np.any(distance <= DEFUSE_CLEAR_M):
            return Decision(STOP_ACTION, hold_ticks=HOLD_TICKS, defuse=True)
        nearest = enemies[
            np.argmin(np.linalg.norm(agents.position[enemies] - agents.position[agent], axis=1))
        ]
        delta = agents.position[nearest] - agents.position[agent]
        agents.yaw[agent] = float(facing_yaw(delta[0], delta[1]))
        return self._hold()

    # ---- legs, paths, holds -------------------------------------------------------------------

    def _follow_legs(self, sim: Simulator, agent: int, node: int) -> Decision:
        legs = self.legs[agent]
        while True:
            leg = legs[int(self.leg[agent])]
            if node != leg.node:
                return self._move(agent, node, leg.node)
            if self.hold_until[agent] < 0:  # just arrived
                self.hold_until[agent] = max(sim.tick + leg.hold_ticks, leg.until_tick)
                if leg.watch is not None:
                    sim.agents.yaw[agent] = self.places.yaw_towards(
                        sim.agents.position[agent], leg.watch
                    )
            wait = int(self.hold_until[agent] - sim.tick)
            if wait > 0:
                return Decision(STOP_ACTION, hold_ticks=min(wait, HOLD_TICKS))
            if self.leg[agent] + 1 >= len(legs):
                return self._hold()  # the route's end: stay
            self.leg[agent] += 1
            self.hold_until[agent] = -1

    @staticmethod
    def _hold() -> Decision:
        return Decision(STOP_ACTION, hold_ticks=HOLD_TICKS)

    def _move(self, agent: int, node: int, target: int) -> Decision:
        """The compass move of the next edge on the shortest path from `node` to `target`."""
        goal, path = self._paths.get(agent, (-1, []))
        if goal != target or node not in path[:-1]:
            path = self.graph.shortest_path(node, target)
            self._paths[agent] = (target, path)
        nxt = path[path.index(node) + 1]
        edges = self.graph.out_edges[node]
        direction = int(np.flatnonzero((edges >= 0) & (self.graph.edge_target[edges] == nxt))[0])
        return Decision(direction)

    def _site_hit(self, sim: Simulator) -> bool:
        """True once an alive T stands on the attacked bomb site (its nav place)."""
        agents = sim.agents
        ts = agents.alive & (agents.side == "T")
        return bool(np.any(self._on_site[agents.node[ts]]))

    def _fetcher(self, sim: Simulator) -> int:
        """The alive T nearest (horizontally) the dropped bomb; -1 if none is alive."""
        agents = sim.agents
        ts = np.flatnonzero(agents.alive & (agents.side == "T"))
        if len(ts) == 0:
            return -1
        delta = agents.position[ts, :2] - sim.bomb.position[:2]
        return int(ts[np.argmin(np.hypot(delta[:, 0], delta[:, 1]))])

    def _node_at(self, position: np.ndarray) -> int:
        """The waypoint under the bomb (cached while the bomb lies in one place)."""
        key = tuple(np.round(position, 6).tolist())
        if self._bomb_node is None or self._bomb_node[0] != key:
            found, _ = self.graph.nearest(np.asarray(position, dtype=np.float64))
            node = int(found[0])
            if node < 0:  # off every floor band: the nearest waypoint in plain 3-D
                node = int(np.argmin(np.linalg.norm(self.graph.positions - position, axis=1)))
            self._bomb_node = (key, node)
        return self._bomb_node[1]
