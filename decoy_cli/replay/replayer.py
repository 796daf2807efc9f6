"""Replay a real round in the simulator, kept in time with the data.

The timed plans of `snap_round` drive the agents through `PlanPolicy`: each move runs at the
speed that reaches the interval's target waypoint by its frame time (capped by the weapon's
CS:GO maximum), a STOP holds until the deadline (so an agent early waits, one late catches up
instead of drifting), and the arrival at every target is logged against its deadline (the
lateness). The anchor implementation moved everyone at knife speed, collapsed STOPs and killed
every agent at the end of its actions; here a survivor survives, and a player who died in the
data is removed at its death time only when combat is off ("scripted" deaths, recorded as such)
— with combat on, only the simulation's own combat kills.

The state of every agent is recorded at every data frame time, so the metrics compare O_t and
S_t on the same clock.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np
import pandas as pd

from decoy_cli.csgo import TICK_RATE
from decoy_cli.errors import EstaError
from decoy_cli.replay.plans import RELOCATE_ACTION, PlayerPlan
from decoy_cli.replay.rounds import RoundPlan, snap_round
from decoy_cli.sim.combat import CombatStep, LineOfSight
from decoy_cli.sim.engine import Decision, Recording, SimConfig, Simulator
from decoy_cli.sim.movement import KinematicMover, PhysicsMover
from decoy_cli.sim.rules import BombRules, RulesConfig, SiteZones
from decoy_cli.sim.state import Agents, SimEvent
from decoy_cli.waypoints.graph import STOP_ACTION, WaypointGraph
from decoy_cli.weapons import max_speed_m_s
from decoy_cli.world.physics import PhysicsWorld

_FOREVER = 10**9


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
            np.maximum(0, self.arrival_tick - self.deadline_tick) / 60.0,
            np.nan,
        )
        return late


class PlanPolicy:
    """Executes timed plans (see decoy_cli/replay/plans.py for the contract)."""

    def __init__(
        self,
        plans: list[PlayerPlan],
        tick_of: Any,
        graph_edge_length: np.ndarray,
        plant_from_tick: int | None = None,
        defuse_from_tick: dict[int, int] | None = None,
        interval_caps: list[np.ndarray] | None = None,
    ) -> None:
        self.plans = plans
        self.interval_caps = interval_caps  # per plan: (T-1,) speed cap of each interval, m/s
        self.tick_of = tick_of  # seconds -> simulator tick
        self.next_action = np.zeros(len(plans), dtype=np.int64)
        self.plant_from_tick = plant_from_tick
        self.defuse_from_tick = defuse_from_tick or {}
        self.logs = []
        # per plan and action: path length of this and the later moves of its interval, and
        # whether it is the last move of its interval
        self._remaining = []
        self._last_move = []
        for plan in plans:
            n_targets = len(plan.target_node)
            arrival = np.full(n_targets, -1, dtype=np.int64)
            if n_targets:
                arrival[0] = tick_of(plan.target_seconds[0])
            self.logs.append(
                AgentLog(arrival, np.array([tick_of(s) for s in plan.target_seconds], np.int64))
            )
            lengths = np.where(
                plan.action_edge >= 0, graph_edge_length[np.maximum(plan.action_edge, 0)], 0.0
            )
            remaining = np.zeros(len(plan.action))
            last_move = np.zeros(len(plan.action), dtype=bool)
            running = 0.0
            seen: set[int] = set()
            for a in range(len(plan.action) - 1, -1, -1):
                interval = int(plan.action_interval[a])
                if a == len(plan.action) - 1 or plan.action_interval[a + 1] != interval:
                    running = 0.0
                running += lengths[a]
                remaining[a] = running
                if plan.action_edge[a] >= 0 and interval not in seen:
                    last_move[a] = True
                    seen.add(interval)
            self._remaining.append(remaining)
            self._last_move.append(last_move)

    def decide(self, sim: Simulator, agent: int) -> Decision:
        plan = self.plans[agent]
        now = sim.tick
        plant = self.plant_from_tick is not None and now >= self.plant_from_tick
        defuse = agent in self.defuse_from_tick and now >= self.defuse_from_tick[agent]
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
            if act == RELOCATE_ACTION and now < deadline:
                return Decision(STOP_ACTION, hold_ticks=deadline - now, plant=plant)
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
            seconds_left = (deadline - now) / 60.0
            speed = None if seconds_left <= 0 else self._remaining[agent][a - 1] / seconds_left
            cap = None if self.interval_caps is None else float(self.interval_caps[agent][interval])
            return Decision(act, speed=speed, max_speed=cap, plant=plant, defuse=defuse)
        return Decision(STOP_ACTION, hold_ticks=_FOREVER, plant=plant, defuse=defuse)

    def _arrive(self, agent: int, interval: int, now: int) -> None:
        """Log the arrival at the target that ends `interval` (first arrival only)."""
        log = self.logs[agent]
        target = interval + 1
        if 0 <= target < len(log.arrival_tick) and log.arrival_tick[target] < 0:
            log.arrival_tick[target] = now


@dataclass
class ReplayResult:
    """A replayed round: the recording at the data's frame clock and what the replay did."""

    plan: RoundPlan
    recording: Recording
    frame_ticks: np.ndarray  # (F,) simulator tick of each data frame
    scripted_death: np.ndarray  # (P,) bool: removed at its data death time, not by combat
    logs: list[AgentLog]
    outcome: Any
    events: list[SimEvent] = field(default_factory=list)
    stuck: np.ndarray | None = None  # (P,) stuck episodes
    recoveries: np.ndarray | None = None  # (P,) recoveries (teleports) by the mover
    played_out_s: float = 0.0  # game seconds simulated after the data's last frame (play_out)

    def lateness_table(self) -> pd.DataFrame:
        """Per player: share of targets reached late, p95 and max lateness (s), relocations."""
        rows = []
        for p, log in enumerate(self.logs):
            late = log.lateness_s
            reached = late[np.isfinite(late)]
            rows.append(
                {
                    "player": self.plan.players[p].name,
                    "targets": len(late),
                    "reached": len(reached),
                    "late_share": float(np.mean(reached > 1 / 60 + 1e-9))
                    if len(reached)
                    else np.nan,
                    "late_p95_s": float(np.percentile(reached, 95)) if len(reached) else np.nan,
                    "late_max_s": float(reached.max()) if len(reached) else np.nan,
                    "relocations": log.relocations,
                }
            )
        return pd.DataFrame(rows)


@dataclass(frozen=True)
class ReplayOptions:
    """How to replay: mechanics on or off, the mover, the damage model, the seed."""

    combat: bool = True
    bomb: bool = True
    # "kinematic" (compiled straight-line motion, agents pass through each other) or "physics"
    # (pybullet capsules that block each other). Measured on the 385 real T rounds with combat
    # and bomb off (benchmarks/replay_study.py): kinematic mean_dist 0.974 m (median 0.675),
    # physics 1.014 m (median 0.694; teammates block each other, 0.5 stuck episodes a round),
    # so the default is kinematic.
    mover: str = "kinematic"
    damage_model: Any = None  # a decoy_cli.sim.combat.DamageModel; None: no shooting
    # With combat on, a round still undecided when the data ends (the replay's fights went
    # otherwise than the real ones) is played on, every agent holding its last waypoint and
    # planting or defusing where the data did, until the rules end it (elimination, the bomb,
    # the clock). Real frames end at the round's end, so without this most replays of a
    # combat round end "undecided" and outcome agreement measures nothing. The result says
    # which outcomes were decided after the data (`ReplayResult.played_out_s`).
    play_out: bool = True
    seed: int = 0
    map_name: str = "de_dust2"


def _tick_of(seconds: float) -> int:
    return round(float(seconds) * TICK_RATE)


def replay_round(
    round_: Any, graph: WaypointGraph, physics: PhysicsWorld, options: ReplayOptions
) -> ReplayResult:
    """Snap, plan and replay one round; see the module docstring.

    A round without frames (an events-only round) raises EstaError: there is nothing to replay.
    """
    if len(round_.frame_seconds) == 0:
        raise EstaError(
            f"round {getattr(round_, 'round_num', '?')} has no frames (events only): "
            "nothing to replay"
        )
    plan = snap_round(round_, graph, physics=physics)
    players = plan.players
    n = len(players)
    first = [int(p.target_frame[0]) if len(p.target_node) else 0 for p in plan.plans]
    start_nodes = np.array(
        [int(p.target_node[0]) if len(p.target_node) else 0 for p in plan.plans], dtype=np.int64
    )

    def at_first(array: np.ndarray, default):
        return [array[i, first[i]] if len(plan.plans[i].target_node) else default for i in range(n)]

    weapons = [w or "Knife" for w in at_first(np.asarray(round_.weapon), "Knife")]
    agents = Agents.create(
        names=[p.name for p in players],
        sides=[p.side for p in players],
        positions=graph.positions[start_nodes],
        nodes=start_nodes,
        weapons=weapons,
        hp=np.clip(at_first(np.asarray(round_.hp), 100), 1, 100),
        armor=np.clip(at_first(np.asarray(round_.armor), 0), 0, 100),
        helmet=at_first(np.asarray(round_.helmet), False),
        has_defuser=at_first(np.asarray(round_.has_defuser), False),
        yaw=np.nan_to_num(np.asarray(at_first(np.asarray(round_.yaw), 0.0), dtype=float)),
    )
    never = np.array([len(p.target_node) == 0 for p in plan.plans])
    agents.alive[never] = False
    agents.hp[never] = 0

    carrier = -1
    has_bomb = np.asarray(round_.has_bomb)
    if options.bomb and has_bomb.size:
        holders = [i for i in range(n) if has_bomb[i, first[i]] and agents.alive[i]]
        carrier = holders[0] if holders else -1
    plant_from = None
    if options.bomb and round_.bomb_plant_tick is not None and len(round_.frame_ticks):
        plant_s = float(np.interp(round_.bomb_plant_tick, round_.frame_ticks, round_.frame_seconds))
        plant_from = _tick_of(plant_s - 3.2 - 1.0)  # allow for the replay's timing tolerance
    defuse_from = _defuse_starts(round_, players)

    frame_ticks = np.array([_tick_of(s) for s in round_.frame_seconds], dtype=np.int64)
    caps = [interval_caps(p, np.asarray(round_.position[i])) for i, p in enumerate(plan.plans)]
    policy = PlanPolicy(plan.plans, _tick_of, graph.edge_length, plant_from, defuse_from, caps)
    if options.mover == "physics":
        mover = PhysicsMover(physics)
    elif options.mover == "kinematic":
        mover = KinematicMover()
    else:
        raise ValueError(f"unknown mover {options.mover!r} (physics or kinematic)")
    round_time = RulesConfig().round_time_s
    if not options.bomb and len(round_.frame_seconds):
        # Without the bomb, a round whose data ran past 115 s (after a plant, which stops the
        # clock) would time out while the players still move: replay it to the end of its data.
        round_time = max(round_time, float(round_.frame_seconds[-1]) + 1.0)
    rules = BombRules(
        SiteZones.from_graph(graph),
        RulesConfig(bomb_enabled=options.bomb, round_time_s=round_time),
    )
    combat = None
    if options.combat and options.damage_model is not None:
        combat = CombatStep(LineOfSight(physics, n), options.damage_model, options.map_name)
    start_tick = int(frame_ticks[0]) if len(frame_ticks) else 0
    sim = Simulator(
        graph,
        agents,
        mover,
        policy,
        rules,
        bomb_carrier=carrier,
        combat=combat,
        config=SimConfig(combat=combat is not None),
        start_tick=start_tick,
        record_ticks=frame_ticks,
        seed=options.seed,
    )
    scripted = np.zeros(n, dtype=bool)
    deaths = {}
    if combat is None:  # movement only: the data's deaths are scripted
        deaths = {
            i: _tick_of(p.death_seconds) for i, p in enumerate(plan.plans) if p.death_frame >= 0
        }
    weapon_frames = np.asarray(round_.weapon)
    frame_of_tick = {int(t): f for f, t in enumerate(frame_ticks)}
    end_tick = int(frame_ticks[-1]) if len(frame_ticks) else start_tick
    try:
        while not sim.done and sim.tick < end_tick:
            # Scripted deaths come before the step of the death frame's tick, which records the
            # frame: the frame that shows the player dead in the data shows it dead here too.
            for i, tick in deaths.items():
                if tick <= sim.tick + 1 and agents.alive[i]:
                    sim.kill(i, "scripted")
                    scripted[i] = True
            sim.step()
            f = frame_of_tick.get(sim.tick)
            if f is not None:  # follow the weapon in hand, as the data shows it
                for i in np.nonzero(agents.alive)[0]:
                    if weapon_frames[i, f]:
                        agents.weapon[i] = weapon_frames[i, f]
                        mover.set_max_speed(int(i), max_speed_m_s(str(weapon_frames[i, f])))
        played_from = sim.tick
        if options.play_out and combat is not None and not sim.done:
            # bounded: the clock ends the round at round_ticks, a bomb at most bomb_ticks later
            limit = max(sim.tick, rules.config.round_ticks) + rules.config.bomb_ticks + 1
            while not sim.done and sim.tick < limit:
                sim.step()
    finally:
        if combat is not None:
            combat.los.close()
        if hasattr(mover, "close"):
            mover.close()
    return ReplayResult(
        plan=plan,
        recording=sim.recording,
        frame_ticks=frame_ticks,
        scripted_death=scripted,
        logs=policy.logs,
        outcome=sim.outcome,
        events=sim.events,
        stuck=np.asarray(mover.stuck_events).copy(),
        recoveries=np.asarray(mover.recoveries).copy(),
        played_out_s=(sim.tick - played_from) / TICK_RATE,
    )


MAX_ZIGZAG = 1.3
"""Largest path-over-straight-line factor by which a replay may outrun the player."""


def interval_caps(plan: PlayerPlan, original: np.ndarray) -> np.ndarray:
    """Speed cap (m/s) of every interval of a plan: how fast the replayed agent may run.

    The weapon's CS:GO maximum is the speed of running on flat ground; real players beat it
    (strafe-jumps, falls: one interval in twenty in the real T rounds), and a path on the
    8-direction lattice is longer than the straight line the player ran (zig-zag, snapping). So
    the cap is the larger of the weapon's maximum and the player's own measured speed over the
    interval, times the path's zig-zag factor: path length over the player's own displacement,
    at most `MAX_ZIGZAG`. (Measured against the straight line between the two snapped
    waypoints instead, snap jitter made agents late: mean_dist 0.974 m against 0.890 m over the
    385 real T rounds.) A replay is never asked to run faster than the player
    did except for the lattice's geometry; what remains infeasible (a detour around a missing
    edge) stays late, and the lateness says so.
    """
    if len(plan.target_node) < 2:
        return np.zeros(0)
    frames = plan.target_frame
    seconds = np.maximum(plan.interval_seconds, 1e-9)
    ran = np.linalg.norm(np.diff(original[frames], axis=0), axis=1) / seconds
    straight = np.where(np.isfinite(ran), ran * seconds, 0.0)
    length = np.nan_to_num(plan.interval_length_m, nan=0.0)
    zigzag = np.clip(
        np.where(straight > 0.05, length / np.maximum(straight, 1e-9), 1.0), 1.0, MAX_ZIGZAG
    )
    ran = np.where(np.isfinite(ran), ran, 0.0)
    return np.maximum(plan.interval_max_speed_m_s, ran) * zigzag


def _defuse_starts(round_: Any, players: list) -> dict[int, int]:
    """Agent -> tick from which it wants to defuse: its `defuse_start` events in the data."""
    events = getattr(round_, "bomb_events", None)
    if events is None or len(events) == 0 or "bombAction" not in events:
        return {}
    starts = events[events["bombAction"] == "defuse_start"]
    out: dict[int, int] = {}
    for i, player in enumerate(players):
        mine = starts[
            (starts.get("playerName") == player.name)
            | (starts.get("playerSteamID") == getattr(player, "steam_id", None))
        ]
        if len(mine):
            seconds = float(np.nanmin(mine["seconds"])) if "seconds" in mine else np.nan
            if np.isfinite(seconds):
                out[i] = _tick_of(seconds) - TICK_RATE
    return out
