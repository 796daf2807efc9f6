"""What each agent of the environment observes: the layout of the observation vector and its
encoding from the simulator's state (`DecoyParallelEnv` documents every entry).

Kept apart from the environment's API so that the encoding can be read, tested and changed on
its own; the environment asks an `ObservationEncoder` for the vectors and masks of a state.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from decoy_cli.sim.engine import Simulator
from decoy_cli.sim.rules import RulesConfig
from decoy_cli.sim.state import Bomb, BombStatus
from decoy_cli.waypoints.graph import STOP_ACTION, WaypointGraph

NUM_ACTIONS = 9
"""Actions 0..7 move along the graph edge in compass direction N, NE, E, SE, S, SW, W, NW;
8 is STOP."""

POSITION_MARGIN_M = 2.0
"""Added around the waypoints' bounding box before normalising positions: room for a jump's
apex above the highest waypoint and for a physics agent's sidestep beyond the outermost one."""

SLOT_FEATURES = 5
"""Per teammate or enemy slot: alive, offset x, y, z, hp."""

BOMB_STATES = ("none", "carried", "dropped", "planted", "defused", "exploded")
"""The bomb status one-hot; "none" when the round has no bomb."""

BOMB_SITES = ("A", "B")


def observation_layout(teammate_slots: int, enemy_slots: int) -> dict[str, slice]:
    """Where each entry lies in the observation vector (see `DecoyParallelEnv`)."""
    sizes = {
        "position": 3,
        "yaw": 2,
        "hp": 1,
        "armor": 1,
        "helmet": 1,
        "defuse_kit": 1,
        "has_bomb": 1,
        "is_ct": 1,
        "needs_decision": 1,
        "teammates": teammate_slots * SLOT_FEATURES,
        "enemies": enemy_slots * SLOT_FEATURES,
        "bomb_state": len(BOMB_STATES),
        "bomb_offset": 3,
        "bomb_site": len(BOMB_SITES),
        "plant_progress": 1,
        "defuse_progress": 1,
        "round_time_left": 1,
        "bomb_time_left": 1,
    }
    layout, start = {}, 0
    for name, size in sizes.items():
        layout[name] = slice(start, start + size)
        start += size
    return layout


def slot_tables(sides: Sequence[str], slots: int) -> tuple[np.ndarray, np.ndarray]:
    """(N, S-1) teammate and (N, S) enemy agent indices of every agent, -1 = unused slot."""
    n = len(sides)
    side = np.asarray(sides)
    mates = np.full((n, slots - 1), -1, dtype=np.int64)
    enemies = np.full((n, slots), -1, dtype=np.int64)
    for agent in range(n):
        same = np.flatnonzero((side == side[agent]) & (np.arange(n) != agent))
        other = np.flatnonzero(side != side[agent])
        mates[agent, : len(same)] = same
        enemies[agent, : len(other)] = other
    return mates, enemies


class ObservationEncoder:
    """The observation vectors and action masks of the agents of one environment."""

    def __init__(
        self, graph: WaypointGraph, sides: Sequence[str], rules: RulesConfig, bomb: bool
    ) -> None:
        self.graph = graph
        self.rules = rules
        self.bomb = bomb
        slots = max(list(sides).count("T"), list(sides).count("CT"))
        self.layout = observation_layout(slots - 1, slots)
        self.size = self.layout["bomb_time_left"].stop
        self._mates, self._enemies = slot_tables(sides, slots)
        lo, hi = graph.positions.min(axis=0), graph.positions.max(axis=0)
        self._centre = (lo + hi) / 2
        self._half = (hi - lo) / 2 + POSITION_MARGIN_M

    def bounds(self) -> tuple[np.ndarray, np.ndarray]:
        """(low, high) float32 bounds of an observation vector."""
        low = np.zeros(self.size, dtype=np.float32)
        for name in ("position", "yaw", "bomb_offset"):
            low[self.layout[name]] = -1.0
        for name in ("teammates", "enemies"):
            block = low[self.layout[name]].reshape(-1, SLOT_FEATURES)
            block[:, 1:4] = -1.0
        return low, np.ones_like(low)

    def encode(self, sim: Simulator, due: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(N, size) float32 observation vectors and (N, 9) int8 action masks of every agent;
        `due` says which agents the engine asks for a decision at the next tick."""
        agents, bomb, cfg, layout = sim.agents, sim.bomb, self.rules, self.layout
        n = agents.count
        pos = agents.position
        obs = np.zeros((n, self.size), dtype=np.float64)
        obs[:, layout["position"]] = np.clip((pos - self._centre) / self._half, -1.0, 1.0)
        yaw = np.radians(agents.yaw)
        obs[:, layout["yaw"]] = np.stack([np.sin(yaw), np.cos(yaw)], axis=1)
        obs[:, layout["hp"].start] = agents.hp / 100.0
        obs[:, layout["armor"].start] = agents.armor / 100.0
        obs[:, layout["helmet"].start] = agents.helmet
        obs[:, layout["defuse_kit"].start] = agents.has_defuser
        has_bomb = self.bomb and bomb.status == BombStatus.CARRIED and bomb.carrier >= 0
        if has_bomb:
            obs[bomb.carrier, layout["has_bomb"].start] = 1.0
        obs[:, layout["is_ct"].start] = agents.side == "CT"
        obs[:, layout["needs_decision"].start] = due
        obs[:, layout["teammates"]] = self._slots(self._mates, pos, agents.alive, agents.hp)
        obs[:, layout["enemies"]] = self._slots(self._enemies, pos, agents.alive, agents.hp)
        obs[:, layout["bomb_state"]] = np.eye(len(BOMB_STATES))[self._bomb_state(bomb)]
        if self._bomb_state(bomb) != 0:
            offset = (bomb.position - pos) / (2 * self._half)
            obs[:, layout["bomb_offset"]] = np.clip(offset, -1.0, 1.0)
        if bomb.site in BOMB_SITES:
            obs[:, layout["bomb_site"].start + BOMB_SITES.index(bomb.site)] = 1.0
        if bomb.planter >= 0:
            obs[:, layout["plant_progress"].start] = bomb.plant_ticks / cfg.plant_ticks
        if bomb.defuser >= 0:
            kit = agents.has_defuser[bomb.defuser]
            needed = cfg.defuse_kit_ticks if kit else cfg.defuse_ticks
            obs[:, layout["defuse_progress"].start] = bomb.defuse_ticks / needed
        clock = bomb.planted_tick if bomb.planted_tick >= 0 else sim.tick
        obs[:, layout["round_time_left"].start] = np.clip(
            (cfg.round_ticks - clock) / cfg.round_ticks, 0.0, 1.0
        )
        if bomb.status == BombStatus.PLANTED:
            left = (bomb.planted_tick + cfg.bomb_ticks - sim.tick) / cfg.bomb_ticks
            obs[:, layout["bomb_time_left"].start] = np.clip(left, 0.0, 1.0)

        masks = np.zeros((n, NUM_ACTIONS), dtype=np.int8)
        masks[:, STOP_ACTION] = 1
        deciding = np.flatnonzero(due)
        masks[deciding, :STOP_ACTION] = self.graph.out_edges[agents.node[deciding]] >= 0
        return obs.astype(np.float32), masks

    def _slots(
        self, table: np.ndarray, pos: np.ndarray, alive: np.ndarray, hp: np.ndarray
    ) -> np.ndarray:
        """(N, slots * 5) features of the agents a slot table names (zeros: dead or unused)."""
        idx = np.maximum(table, 0)
        valid = (table >= 0) & alive[idx]
        offset = np.clip((pos[idx] - pos[:, None, :]) / (2 * self._half), -1.0, 1.0)
        features = np.concatenate(
            [np.ones((*idx.shape, 1)), offset, (hp[idx] / 100.0)[..., None]], axis=2
        )
        return (features * valid[..., None]).reshape(len(table), -1)

    def _bomb_state(self, bomb: Bomb) -> int:
        """Index into BOMB_STATES."""
        if not self.bomb or (bomb.status == BombStatus.CARRIED and bomb.carrier < 0):
            return 0
        return 1 + int(bomb.status)
