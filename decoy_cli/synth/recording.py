"""A scripted round's frames and events as ESTA round data, the way awpy records them.

The state of all ten players every 30 simulator ticks (0.5 s: 2 frames per second,
64 demo ticks apart at 128 tick), from freeze-time end to the round end, as awpy records frames:
none after the end. Combat runs on the frame ticks, so the last kill is always in a frame; a
detonation or defuse between two frames changes no player's state. The events (damages, kills,
bomb events) keep their own ticks. Simulator ticks (60 Hz) become demo ticks (128 Hz) by
rounding; a frame tick is exact.
"""

from __future__ import annotations

import numpy as np

from decoy_cli.csgo import TICK_RATE
from decoy_cli.esta.records import (
    BOMB_ACTIONS,
    FREEZE_TIME_S,
    TRADE_TIME_S,
    BombEventRecord,
    DamageRecord,
    KillRecord,
)
from decoy_cli.geometry import facing_yaw, wrap_180
from decoy_cli.sim.combat import HIT_GROUPS
from decoy_cli.sim.engine import Simulator
from decoy_cli.sim.rules import SiteZones
from decoy_cli.sim.state import Agents, BombStatus, SimEvent
from decoy_cli.waypoints.graph import WaypointGraph

FRAME_EVERY_TICKS = 30
"""Simulator ticks between recorded frames: 0.5 s, ESTA's 2 frames per second."""

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


class Recorder:
    """Snapshots of the agents and the bomb every frame, turned into EstaRoundRecord arrays."""

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


class EventLog:
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
    seen = facing_yaw(attacker[0] - victim[0], attacker[1] - victim[1]) - victim_yaw
    left = wrap_180(seen) >= 0.0
    return f"{'Left' if left else 'Right'}{name}"
