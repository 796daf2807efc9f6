"""The timed plan as an engine policy: each agent reaches each data frame's waypoint by its time.

`PlanPolicy` executes the timed plans of `snap_round` (see decoy_cli/replay/plans.py for the
contract): each move runs at the speed that reaches the interval's target waypoint by its frame
time (capped by the weapon's CS:GO maximum, or the interval's cap), a STOP holds until the
deadline (so an agent early waits, one late catches up instead of drifting), and the arrival
at every target is logged against its deadline in an `AgentLog` (the lateness).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, replace

import numpy as np

from decoy_cli.csgo import TICK_RATE
from decoy_cli.replay.bomb import FOREVER, DataPlant
from decoy_cli.replay.plans import RELOCATE_ACTION, PlayerPlan
from decoy_cli.sim.engine import Decision, Simulator
from decoy_cli.sim.state import BombStatus
from decoy_cli.waypoints.graph import STOP_ACTION, EdgeKind, WaypointGraph


@dataclass
class AgentLog:
    """What happened to one agent's plan: arrival at each target against its deadline."""

    arrival_tick: np.ndarray  # (T,) tick the agent stood at each target, -1 = never
    deadline_tick: np.ndarray  # (T,)
    relocations: int = 0

    @property
    def lateness_s(self) -> np.ndarray:
        """(T,) seconds late at each reached target (0 when on time or early), NaN if unreached."""
        late = np.where(
            self.arrival_tick >= 0,
            np.maximum(0, self.arrival_tick - self.deadline_tick) / TICK_RATE,
            np.nan,
        )
        return late


class PlanPolicy:
    """Executes timed plans (see decoy_cli/replay/plans.py for the contract)."""

    def __init__(
        self,
        plans: list[PlayerPlan],
        tick_of: Callable[[float], int],
        graph: WaypointGraph,
        plant: DataPlant | None = None,
        defuse_window: dict[int, tuple[int, int]] | None = None,
        interval_caps: list[np.ndarray] | None = None,
    ) -> None:
        self.plans = plans
        self.interval_caps = interval_caps  # per plan: (T-1,) speed cap of each interval, m/s
        self.tick_of = tick_of  # seconds -> simulator tick
        self.next_action = np.zeros(len(plans), dtype=np.int64)
        self.plant = plant
        self.defuse_window = defuse_window or {}  # agent -> ticks it wants to defuse
        self.logs = []
        # per plan and action: the run (metres at the agent's own speed) of this and the later
        # moves of its interval, and whether it is the last move of its interval
        self._remaining = []
        self._remaining_air = []  # seconds of those moves spent rising, falling, climbing
        self._last_move = []
        self._stood: list[list[tuple[int, int]]] = [[] for _ in plans]  # (interval, tick)
        for plan in plans:
            n_targets = len(plan.target_node)
            arrival = np.full(n_targets, -1, dtype=np.int64)
            if n_targets:
                arrival[0] = tick_of(plan.target_seconds[0])
            self.logs.append(
                AgentLog(arrival, np.array([tick_of(s) for s in plan.target_seconds], np.int64))
            )
            moves = plan.action_edge >= 0
            edge = np.maximum(plan.action_edge, 0)
            lengths = np.where(moves, graph.edge_run_m[edge], 0.0)
            airs = np.where(moves, graph.edge_fixed_s[edge], 0.0)
            remaining = np.zeros(len(plan.action))
            remaining_air = np.zeros(len(plan.action))
            last_move = np.zeros(len(plan.action), dtype=bool)
            running = running_air = 0.0
            seen: set[int] = set()
            for a in range(len(plan.action) - 1, -1, -1):
                interval = int(plan.action_interval[a])
                if a == len(plan.action) - 1 or plan.action_interval[a + 1] != interval:
                    running = running_air = 0.0
                running += lengths[a]
                running_air += airs[a]
                remaining[a] = running
                remaining_air[a] = running_air
                if plan.action_edge[a] >= 0 and interval not in seen:
                    last_move[a] = True
                    seen.add(interval)
            self._remaining.append(remaining)
            self._remaining_air.append(remaining_air)
            self._last_move.append(last_move)

    def decide(self, sim: Simulator, agent: int) -> Decision:
        plan = self.plans[agent]
        now = sim.tick
        for interval, tick in self._stood[agent]:  # it lived through the hold: it stood there
            self._arrive(agent, interval, tick)
        self._stood[agent].clear()
        plant = self.plant is not None and now >= self.plant.start_tick
        first, last = self.defuse_window.get(agent, (FOREVER, FOREVER))
        defuse = first <= now <= last
        bomb, config = sim.bomb, sim.rules.config
        if plant and bomb.planter == agent:
            # planting, as the real player did: hold still until the plant completes, then
            # the plan resumes and catches up
            left = max(1, config.plant_ticks - bomb.plant_ticks)
            self._stand_through(sim, agent, now + left)
            return Decision(STOP_ACTION, hold_ticks=left, plant=True)
        if defuse and bomb.defuser == agent:  # likewise while defusing
            kit = bool(sim.agents.has_defuser[agent])
            left = (config.defuse_kit_ticks if kit else config.defuse_ticks) - bomb.defuse_ticks
            hold = max(1, min(left, last - now + 1))
            self._stand_through(sim, agent, now + hold)
            return Decision(STOP_ACTION, hold_ticks=hold, defuse=True)
        decision = self._follow_plan(sim, agent, plan, now, plant, defuse)
        if decision.action == STOP_ACTION:
            # wake when the data's plant or this agent's defuse starts or ends, so the wish to
            # plant or defuse follows the data's times
            wakes = [t for t in (first, last + 1) if now < t < now + decision.hold_ticks]
            if self.plant is not None and now < self.plant.start_tick < now + decision.hold_ticks:
                wakes.append(self.plant.start_tick)
            if wakes:
                decision = replace(decision, hold_ticks=min(wakes) - now)
        return decision

    def _stand_through(self, sim: Simulator, agent: int, until: int) -> None:
        """An agent held still (planting, defusing) until tick `until` reaches the plan's
        targets it stands at whose stand ends by then as they come: the real player stood there
        too. They are logged, from now, at its next decision (one it is killed before never
        reaches them); without this they would wait for the hold's end and count as late."""
        plan, a = self.plans[agent], int(self.next_action[agent])
        node, stood = int(sim.agents.node[agent]), self._stood[agent]
        if a > 0 and self._last_move[agent][a - 1] and int(plan.action_node[a - 1]) == node:
            stood.append((int(plan.action_interval[a - 1]), sim.tick))  # the move's end
        while (
            a < len(plan.action)
            and int(plan.action[a]) == STOP_ACTION
            and int(plan.action_node[a]) == node
            and self.tick_of(plan.action_deadline_s[a]) <= until
        ):
            stood.append((int(plan.action_interval[a]), sim.tick))
            a += 1
        self.next_action[agent] = a

    def _plants_here(self, sim: Simulator, agent: int, interval: int) -> bool:
        """Whether the carrier, about to leave its plan's plant spot by a move of `interval`,
        must stay and plant first: the data's plant has begun, this agent planted it, carries
        the bomb, stands at the plant target inside a site, and has not planted yet. A carrier
        that arrived late plants late rather than walking on with the bomb."""
        data = self.plant
        if data is None or agent != data.agent or interval < data.target:
            return False
        bomb = sim.bomb
        return (
            sim.tick >= data.start_tick
            and bomb.status == BombStatus.CARRIED
            and bomb.carrier == agent
            and int(sim.agents.node[agent]) == int(self.plans[agent].target_node[data.target])
            and bool(sim.rules.zones.site_of(sim.agents.position[agent])[0])
        )

    def _follow_plan(
        self, sim: Simulator, agent: int, plan: PlayerPlan, now: int, plant: bool, defuse: bool
    ) -> Decision:
        first_deadline = self.logs[agent].deadline_tick[0] if len(plan.target_node) else 0
        if now < first_deadline:  # not on stage yet
            return Decision(STOP_ACTION, hold_ticks=int(first_deadline - now), plant=plant)
        a = int(self.next_action[agent])
        if a > 0 and self._last_move[agent][a - 1]:  # just finished an interval's moves
            self._arrive(agent, int(plan.action_interval[a - 1]), now)
        while a < len(plan.action):
            act = int(plan.action[a])
            interval = int(plan.action_interval[a])
            deadline = self.tick_of(plan.action_deadline_s[a])
            data = self.plant
            if data is not None and agent == data.agent and interval == data.arrive_by - 1:
                deadline = min(deadline, data.start_tick)  # at the plant spot by its start
            if act == RELOCATE_ACTION:
                # placed in the tick before the player crossed, so it stands on the target
                # when that frame is recorded
                cross = min(deadline, self.tick_of(plan.interval_cross_s[interval])) - 1
                if now < cross:
                    return Decision(STOP_ACTION, hold_ticks=cross - now, plant=plant)
            a += 1
            self.next_action[agent] = a
            if act == RELOCATE_ACTION:
                sim.relocate(agent, int(plan.action_node[a - 1]))
                self.logs[agent].relocations += 1
                self._arrive(agent, interval, now)
                continue
            if act == STOP_ACTION:
                self._arrive(agent, interval, now)  # standing still: already at the target
                if deadline > now:
                    return Decision(
                        STOP_ACTION, hold_ticks=deadline - now, plant=plant, defuse=defuse
                    )
                continue
            if self._plants_here(sim, agent, interval):
                self.next_action[agent] = a - 1  # the move waits until the plant completes
                return Decision(STOP_ACTION, hold_ticks=1, plant=True)
            spare = self._spare_before_a_fall(sim.graph, agent, a - 1, deadline - now)
            if spare > 0:  # nothing left to run but the fall: it lands on the deadline
                self.next_action[agent] = a - 1
                return Decision(STOP_ACTION, hold_ticks=spare, plant=plant, defuse=defuse)
            speed = self._speed(sim.graph, agent, a - 1, (deadline - now) / TICK_RATE)
            cap = None if self.interval_caps is None else float(self.interval_caps[agent][interval])
            return Decision(act, speed=speed, max_speed=cap, plant=plant, defuse=defuse)
        return Decision(STOP_ACTION, hold_ticks=FOREVER, plant=plant, defuse=defuse)

    def _speed(
        self, graph: WaypointGraph, agent: int, action: int, seconds_left: float
    ) -> float | None:
        """The speed of a move that reaches its interval's end in `seconds_left`: the run left
        over the time its rises, falls and climbs leave (None: as fast as it can). A ladder is
        climbed at the climbing speed (None), the time the plan gave it; with nothing left to
        run, slow enough to reach the interval's end by its deadline, as a run would."""
        run, fixed = self._remaining[agent][action], self._remaining_air[agent][action]
        edge = int(self.plans[agent].action_edge[action])
        if graph.edge_kind[edge] == EdgeKind.LADDER:
            if run > 0:
                return None
            run, fixed = float(graph.edge_length[edge]), fixed - float(graph.edge_climb_s[edge])
        running_s = seconds_left - fixed
        return run / running_s if running_s > 0 else None

    def _spare_before_a_fall(
        self, graph: WaypointGraph, agent: int, action: int, ticks_left: int
    ) -> int:
        """Ticks to wait at a ledge before running off it, when the fall is all that is left of
        the interval and lands before its deadline: a player with time to spare before a drop
        does not land early and stand below (0 for every other move)."""
        edge = int(self.plans[agent].action_edge[action])
        if not graph.off_a_ledge[edge] or self._remaining[agent][action] > 0:
            return 0
        fall = int(np.ceil(self._remaining_air[agent][action] * TICK_RATE))
        return max(ticks_left - fall, 0)

    def _arrive(self, agent: int, interval: int, now: int) -> None:
        """Log the arrival at the target that ends `interval` (first arrival only)."""
        log = self.logs[agent]
        target = interval + 1
        if 0 <= target < len(log.arrival_tick) and log.arrival_tick[target] < 0:
            log.arrival_tick[target] = now
