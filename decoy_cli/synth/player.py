"""Play one scripted round in the simulator and record it as ESTA round data.

`ScriptedPolicy` drives the agents of a `RoundPlan` (decoy_cli/synth/routes.py) through the
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

Whatever the simulator's rules say ends the round (elimination, detonation, defuse, time); the
winner and reason are the simulator's. Combat runs when a damage model is given.

Recording: the state of all ten players every 30 simulator ticks (0.5 s: 2 frames per second,
64 demo ticks apart at 128 tick), from freeze-time end to the round end, as awpy records frames:
none after the end. Combat runs on the frame ticks, so the last kill is always in a frame; a
detonation or defuse between two frames changes no player's state. The events (damages, kills,
bomb events) keep their own ticks. Simulator ticks (60 Hz)
become demo ticks (128 Hz) by rounding; a frame tick is exact.
"""

from __future__ import annotations

from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass, field
from typing import cast

import numpy as np

from decoy_cli.csgo import TICK_RATE
from decoy_cli.esta.frames import Side
from decoy_cli.esta.writer import (
    BOMB_ACTIONS,
    FREEZE_TIME_S,
    TRADE_TIME_S,
    BombEventRecord,
    DamageRecord,
    KillRecord,
    PlayerRecord,
    RoundRecord,
)
from decoy_cli.sim.combat import HIT_GROUPS, DamageModel
from decoy_cli.sim.engine import Decision, Simulator
from decoy_cli.sim.rules import SiteZones
from decoy_cli.sim.setup import RoundSetup, open_round
from decoy_cli.sim.state import Agents, BombStatus, SimEvent
from decoy_cli.synth.loadouts import START_VALUE, Loadout
from decoy_cli.synth.routes import SITE_PLACES, Leg, Places, RoundPlan
from decoy_cli.waypoints.graph import STOP_ACTION, WaypointGraph
from decoy_cli.world.physics import PhysicsWorld

FRAME_EVERY_TICKS = 30
"""Simulator ticks between recorded frames: 0.5 s, ESTA's 2 frames per second."""

HOLD_TICKS = 30
"""Longest STOP the policy gives: agents look at the round again every 0.5 s."""

DEFUSE_CLEAR_M = 10.0
"""A CT starts a defuse only when no alive T stands within this distance of the bomb."""

DEMO_TICK_RATE = 128
FREEZE_TIME_TICKS = int(FREEZE_TIME_S) * DEMO_TICK_RATE
"""Demo ticks from the round start to freeze-time end (mp_freezetime 15)."""

RESTART_DELAY_TICKS = 7 * DEMO_TICK_RATE
"""Demo ticks from the round end to its official end (mp_round_restart_delay 7)."""

ASSIST_MIN_DAMAGE = 41
"""CS:GO credits an assist for more than 40 damage to the victim."""

TRADE_TICKS = TRADE_TIME_S * TICK_RATE
"""awpy's trade time, in simulator ticks."""

_SIM_BOMB_ACTIONS = frozenset(BOMB_ACTIONS)
"""The simulator names its bomb events as awpy names its bomb actions."""


@dataclass(frozen=True)
class Team:
    """The ten players of the match: names, steamIDs, sides (T first, then CT)."""

    names: tuple[str, ...]
    steam_ids: tuple[int, ...]
    sides: tuple[str, ...]


@dataclass
class PlayedRound:
    """A scripted round as played: the ESTA round data and what the script chose."""

    record: RoundRecord
    plan: RoundPlan
    buys: dict[str, str]
    invalid_actions: int

    @property
    def end_seconds(self) -> float:
        """Seconds from freeze-time end to the round end."""
        return (self.record.end_tick - self.record.freeze_end_tick) / DEMO_TICK_RATE


class ScriptedPolicy:
    """The engine policy of a scripted round (see the module docstring)."""

    def __init__(self, graph: WaypointGraph, places: Places, plan: RoundPlan) -> None:
        self.graph = graph
        self.places = places
        self.plan = plan
        n = len(plan.routes)
        self.legs: list[list[Leg]] = [list(route) for route in plan.routes]
        self.leg = np.zeros(n, dtype=np.int64)
        self.hold_until = np.full(n, -1, dtype=np.int64)  # -1: not yet arrived at the leg
        self.routed_to_plant = {plan.carrier}
        self.rotated: set[int] = set()
        self._site_place = places.graph.place_names.index(SITE_PLACES[plan.site])
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
        agents.yaw[agent] = float(np.degrees(np.arctan2(delta[1], delta[0])))
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
        return bool(np.any(self.graph.node_place[agents.node[ts]] == self._site_place))

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
            index, _ = self.graph.nearest(np.asarray(position, dtype=np.float64))
            if index[0] < 0:  # off every floor band: the nearest waypoint in plain 3-D
                index = [int(np.argmin(np.linalg.norm(self.graph.positions - position, axis=1)))]
            self._bomb_node = (key, int(index[0]))
        return self._bomb_node[1]


@dataclass(frozen=True, kw_only=True)
class RoundScript:
    """What a scripted round is played from: the routes, the loadouts and the team."""

    places: Places
    plan: RoundPlan
    loadouts: list[Loadout]
    team: Team
    buys: dict[str, str] = field(default_factory=dict)


def scripted_setup(graph: WaypointGraph, damage_model: DamageModel | None) -> RoundSetup:
    """How scripted rounds are simulated: kinematic mover, bomb on, combat (with a damage
    model) once per recorded frame."""
    return RoundSetup(
        graph=graph,
        mover="kinematic",
        combat=damage_model is not None,
        bomb=True,
        damage_model=damage_model,
        combat_every_ticks=FRAME_EVERY_TICKS,
    )


def scripted_agents(graph: WaypointGraph, script: RoundScript) -> Agents:
    """The agents of a scripted round before its first tick: on their spawn waypoints, facing
    their first leg, with their loadouts."""
    plan, loadouts, team = script.plan, script.loadouts, script.team
    start_nodes = np.array([route[0].node for route in plan.routes], dtype=np.int64)
    positions = graph.positions[start_nodes]
    first_moves = [route[1].node if len(route) > 1 else route[0].node for route in plan.routes]
    yaw = np.degrees(
        np.arctan2(
            graph.positions[first_moves, 1] - positions[:, 1],
            graph.positions[first_moves, 0] - positions[:, 0],
        )
    )
    return Agents.create(
        names=list(team.names),
        sides=list(team.sides),
        positions=positions,
        nodes=start_nodes,
        weapons=[lo.active for lo in loadouts],
        armor=np.array([lo.armor for lo in loadouts]),
        helmet=np.array([lo.helmet for lo in loadouts]),
        has_defuser=np.array([lo.defuse_kit for lo in loadouts]),
        yaw=yaw,
    )


@contextmanager
def open_scripted_round(
    setup: RoundSetup, script: RoundScript, *, seed: int, physics: PhysicsWorld | None = None
) -> Iterator[Simulator]:
    """The simulator of a scripted round before its first tick (policy `ScriptedPolicy`)."""
    policy = ScriptedPolicy(setup.graph, script.places, script.plan)
    agents = scripted_agents(setup.graph, script)
    with open_round(
        setup, agents, policy, physics=physics, bomb_carrier=script.plan.carrier, seed=seed
    ) as sim:
        yield sim


def play_round(
    setup: RoundSetup,
    script: RoundScript,
    *,
    round_num: int,
    start_tick: int,
    seed: int,
    physics: PhysicsWorld | None = None,
) -> PlayedRound:
    """Play one round of `script` and record it (demo ticks from `start_tick`).

    `physics` lends a pybullet world of the map for line of sight (without it, one is opened
    for the round when combat needs it).
    """
    graph, plan, loadouts, team = setup.graph, script.plan, script.loadouts, script.team
    n = len(plan.routes)
    zones = SiteZones.from_graph(graph)
    freeze_end = start_tick + FREEZE_TIME_TICKS
    with open_scripted_round(setup, script, seed=seed, physics=physics) as sim:
        agents = sim.agents
        recorder = _Recorder(graph, zones, agents)
        events = _EventLog(freeze_end, agents)
        recorder.snapshot(sim)
        while not sim.done:
            hp_before = agents.hp.copy()
            new = sim.step()
            events.add(sim, new, hp_before)
            if sim.tick % FRAME_EVERY_TICKS == 0:
                recorder.snapshot(sim)
    if sim.outcome is None:
        raise RuntimeError(f"round {round_num} did not end within the simulator's bound")

    end_tick = events.demo_tick(sim.outcome.tick)
    players = [
        PlayerRecord(
            name=team.names[i],
            steam_id=team.steam_ids[i],
            side=cast(Side, team.sides[i]),
            inventory=loadouts[i].inventory,
            equipment_value=loadouts[i].value,
            start_equipment_value=START_VALUE,
            cash_spent=max(0, loadouts[i].value - START_VALUE),
        )
        for i in range(n)
    ]
    frames = recorder.arrays()
    record = RoundRecord(
        round_num=round_num,
        start_tick=start_tick,
        freeze_end_tick=freeze_end,
        end_tick=end_tick,
        end_official_tick=end_tick + RESTART_DELAY_TICKS,
        frame_ticks=np.array([events.demo_tick(t) for t in recorder.ticks], dtype=np.int64),
        players=players,
        winning_side=cast(Side, sim.outcome.winner),
        end_reason=sim.outcome.reason,
        bomb_plant_tick=events.plant_tick,
        damages=events.damages,
        kills=events.kills,
        bomb_events=events.bomb_events,
        **frames,
    )
    invalid = sum(1 for e in sim.events if e.kind == "invalid_action")
    return PlayedRound(record, plan, dict(script.buys), invalid)


class _Recorder:
    """Snapshots of the agents and the bomb every frame, turned into RoundRecord arrays."""

    def __init__(self, graph: WaypointGraph, zones: SiteZones, agents: Agents) -> None:
        self.graph = graph
        self.zones = zones
        self.agents = agents
        self.ticks: list[int] = []
        self.rows: list[dict[str, np.ndarray]] = []
        spawns = [
            graph.regions.get(name, np.zeros(0, np.int64)) for name in ("t_spawn", "ct_spawn")
        ]
        self._in_spawn = np.zeros(graph.num_nodes, dtype=bool)
        self._in_spawn[np.concatenate(spawns)] = True
        self._places = np.array([*graph.place_names, ""], dtype=object)

    def snapshot(self, sim: Simulator) -> None:
        agents = self.agents
        bomb = sim.bomb
        n = agents.count
        carried = bomb.status == BombStatus.CARRIED and bomb.carrier >= 0
        has_bomb = np.zeros(n, dtype=bool)
        if carried:
            has_bomb[bomb.carrier] = True
        in_zone = np.zeros(n, dtype=bool)
        if carried:  # awpy sets isInBombZone for the carrier only (see decoy_cli/sim/rules.py)
            in_zone[bomb.carrier] = bool(self.zones.site_of(agents.position[bomb.carrier])[0])
        planting = np.zeros(n, dtype=bool)
        defusing = np.zeros(n, dtype=bool)
        if bomb.planter >= 0:
            planting[bomb.planter] = True
        if bomb.defuser >= 0:
            defusing[bomb.defuser] = True
        seconds = sim.tick / TICK_RATE
        buy_time = seconds <= 20.0  # the buy time after freeze-time end
        place = self.graph.node_place[agents.node]
        self.ticks.append(sim.tick)
        self.rows.append(
            {
                "position": agents.position.copy(),
                "yaw": agents.yaw.copy(),
                "hp": agents.hp.copy(),
                "armor": np.where(agents.alive, agents.armor, 0),
                "helmet": agents.helmet & agents.alive,
                "has_defuser": agents.has_defuser & agents.alive,
                "weapon": np.where(agents.alive, agents.weapon.astype(str), ""),
                "alive": agents.alive.copy(),
                "has_bomb": has_bomb,
                "planting": planting,
                "defusing": defusing,
                "in_bomb_zone": in_zone,
                "in_buy_zone": agents.alive & buy_time & self._in_spawn[agents.node],
                "place": self._places[np.where(place >= 0, place, len(self._places) - 1)],
                "bomb_position": bomb.position.copy(),
                "bomb_planted": np.array(bomb.planted_tick >= 0),
                "bombsite": np.array(bomb.site if bomb.planted_tick >= 0 else ""),
            }
        )

    def arrays(self) -> dict[str, np.ndarray]:
        """(P, F, ...) player arrays and (F, ...) bomb arrays of every snapshot."""
        out = {}
        for name in self.rows[0]:
            stacked = np.stack([row[name] for row in self.rows])
            out[name] = stacked if name.startswith("bomb") else np.moveaxis(stacked, 0, 1)
        out["bombsite"] = out["bombsite"].astype(str)
        out["weapon"] = out["weapon"].astype(str)
        return out


class _EventLog:
    """Simulator events turned into ESTA event records, with the awpy extras they need."""

    def __init__(self, freeze_end: int, agents: Agents) -> None:
        self.freeze_end = freeze_end
        self.agents = agents
        self.damages: list[DamageRecord] = []
        self.kills: list[KillRecord] = []
        self.bomb_events: list[BombEventRecord] = []
        self.plant_tick: int | None = None
        self._planter = -1
        self._dealt = np.zeros((agents.count, agents.count), dtype=np.int64)
        self._kill_ticks: list[tuple[int, int, int]] = []  # (sim tick, killer, victim)

    def demo_tick(self, sim_tick: int) -> int:
        """The demo tick (128 Hz, from freeze-time end) of a simulator tick (60 Hz), rounded."""
        return self.freeze_end + (2 * sim_tick * DEMO_TICK_RATE + TICK_RATE) // (2 * TICK_RATE)

    def add(self, sim: Simulator, events: list[SimEvent], hp_before: np.ndarray) -> None:
        remaining = hp_before.astype(np.int64)
        for event in events:
            if event.kind == "damage":
                self._damage(event, remaining)
            elif event.kind == "kill":
                self._kill(event)
            elif event.kind in _SIM_BOMB_ACTIONS:
                self._bomb(sim, event)

    def _state(self, agent: int) -> tuple[tuple[float, ...], float]:
        return tuple(self.agents.position[agent].tolist()), float(self.agents.yaw[agent])

    def _damage(self, event: SimEvent, remaining: np.ndarray) -> None:
        attacker, victim = event.agent, event.other
        damage = int(event.data["damage"])
        taken = min(damage, int(remaining[victim]))
        remaining[victim] -= taken
        self._dealt[attacker, victim] += taken
        a_pos, a_yaw = self._state(attacker)
        v_pos, v_yaw = self._state(victim)
        self.damages.append(
            DamageRecord(
                tick=self.demo_tick(event.tick),
                attacker=attacker,
                victim=victim,
                weapon=str(event.data["weapon"]),
                hp_damage=damage,
                hp_damage_taken=taken,
                hit_group=_awpy_hit_group(int(event.data["hit_group"]), a_pos, v_pos, v_yaw),
                attacker_position=a_pos,
                victim_position=v_pos,
                attacker_yaw=a_yaw,
                victim_yaw=v_yaw,
            )
        )

    def _kill(self, event: SimEvent) -> None:
        killer, victim = event.agent, event.other
        side = self.agents.side
        mates = np.flatnonzero((side == side[killer]) & (np.arange(len(side)) != killer))
        dealt = self._dealt[mates, victim]
        assister = (
            int(mates[np.argmax(dealt)]) if len(mates) and dealt.max() >= ASSIST_MIN_DAMAGE else -1
        )
        traded = -1
        for tick, earlier_killer, earlier_victim in reversed(self._kill_ticks):
            if event.tick - tick > TRADE_TICKS:
                break
            if earlier_killer == victim and side[earlier_victim] == side[killer]:
                traded = earlier_victim
                break
        a_pos, a_yaw = self._state(killer)
        v_pos, v_yaw = self._state(victim)
        self.kills.append(
            KillRecord(
                tick=self.demo_tick(event.tick),
                attacker=killer,
                victim=victim,
                weapon=str(event.data["weapon"]),
                attacker_position=a_pos,
                victim_position=v_pos,
                attacker_yaw=a_yaw,
                victim_yaw=v_yaw,
                is_headshot=int(event.data["hit_group"]) == HIT_GROUPS.index("Head"),
                is_first_kill=not self.kills,
                assister=assister,
                traded=traded,
            )
        )
        self._kill_ticks.append((event.tick, killer, victim))

    def _bomb(self, sim: Simulator, event: SimEvent) -> None:
        player = event.agent
        if event.kind == "plant":
            self._planter = player
            self.plant_tick = self.demo_tick(event.tick)
        if event.kind == "explode":  # awpy names the planter; the bomb lies where it was planted
            player = self._planter
            position = tuple(sim.bomb.position.tolist())
        else:
            position = self._state(player)[0]
        site = str(event.data.get("site", "")) or sim.bomb.site
        self.bomb_events.append(
            BombEventRecord(self.demo_tick(event.tick), player, event.kind, site, position)
        )


def _awpy_hit_group(
    code: int, attacker: tuple[float, ...], victim: tuple[float, ...], victim_yaw: float
) -> str:
    """awpy's hit group of a simulator hit group: an arm or leg hit is on the victim's side
    that faces the attacker (left when the attacker is counter-clockwise of its view)."""
    name = HIT_GROUPS[code]
    if name not in ("Arm", "Leg"):
        return name
    bearing = np.degrees(np.arctan2(attacker[1] - victim[1], attacker[0] - victim[0])) - victim_yaw
    left = (bearing + 180.0) % 360.0 - 180.0 >= 0.0
    return f"{'Left' if left else 'Right'}{name}"
