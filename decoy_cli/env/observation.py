"""What each agent of the environment observes: the layout of the observation vector and its
encoding from the simulator's state (`DecoyParallelEnv` documents every entry).

Kept apart from the environment's API so that the encoding can be read, tested and changed on
its own. An `ObservationEncoder` holds the layout and what the compiled `encode_into` needs of
it (`kernel_arrays`) and of the round (`round_inputs`); the environment's steps (`env_step`)
encode each state with them.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from decoy_cli.compiled import njit_cached
from decoy_cli.sim.engine import Simulator
from decoy_cli.sim.rules import RulesConfig
from decoy_cli.sim.schedule import is_due
from decoy_cli.sim.state import Bomb, BombStatus
from decoy_cli.waypoints.graph import WaypointGraph

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
        self._is_ct = np.asarray(sides) == "CT"
        self._starts = np.array([self.layout[name].start for name in _PER_AGENT], dtype=np.int64)
        self._bomb_starts = np.array([self.layout[name].start for name in _BOMB], dtype=np.int64)
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

    def kernel_arrays(self) -> tuple[np.ndarray, ...]:
        """What `encode_into` takes of this encoder, for compiled callers (`env_step`): the
        starts of the per-agent and round entries, who is a CT, the slot tables, the centre and
        half size of the positions' box."""
        return (
            self._starts, self._bomb_starts, self._is_ct, self._mates, self._enemies, self._centre,
            self._half,
        )  # fmt: skip

    def round_inputs(self, sim: Simulator) -> tuple[int, int, np.ndarray]:
        """What `encode_into` needs of the bomb and the round besides the tick: the bomb state's
        index into BOMB_STATES, its carrier (-1 unless carried) and `ROUND_INPUTS`. None of
        them changes on ticks when nothing but decisions and motion happen."""
        agents, bomb, cfg = sim.agents, sim.bomb, self.rules
        state = self._bomb_state(bomb)
        site = BOMB_SITES.index(bomb.site) if bomb.site in BOMB_SITES else -1
        plant = bomb.plant_ticks / cfg.plant_ticks if bomb.planter >= 0 else 0.0
        defuse = 0.0
        if bomb.defuser >= 0:
            kit = agents.has_defuser[bomb.defuser]
            defuse = bomb.defuse_ticks / (cfg.defuse_kit_ticks if kit else cfg.defuse_ticks)
        planted = bomb.status == BombStatus.PLANTED
        inputs = np.array(
            [site, plant, defuse, bomb.planted_tick, planted, cfg.round_ticks, cfg.bomb_ticks],
            dtype=np.float64,
        )
        return state, bomb.carrier if state == 1 else -1, inputs

    def _bomb_state(self, bomb: Bomb) -> int:
        """Index into BOMB_STATES."""
        if not self.bomb or (bomb.status == BombStatus.CARRIED and bomb.carrier < 0):
            return 0
        return 1 + int(bomb.status)


_PER_AGENT = (
    "position", "yaw", "hp", "armor", "helmet", "defuse_kit", "has_bomb", "is_ct",
    "needs_decision", "teammates", "enemies", "bomb_offset",
)  # fmt: skip
"""The entries `_agent_features` fills, in the order of its `starts`."""


_BOMB = (
    "bomb_state", "bomb_site", "plant_progress", "defuse_progress", "round_time_left",
    "bomb_time_left",
)  # fmt: skip
"""The round's entries, the same for every agent, in the order of `encode_into`'s `bomb_starts`."""


ROUND_INPUTS = ("bomb_site", "plant_progress", "defuse_progress", "planted_tick", "planted",
                "round_ticks", "bomb_ticks")  # fmt: skip
"""The entries of `encode_into`'s `round_inputs`: the bomb site's index or -1, plant and defuse
progress, the tick of the plant or -1, 1 while the bomb is planted, the round's and the bomb's
time in ticks."""


@njit_cached
def encode_into(r, e, bomb, done, tick, out):
    """Write the observation vectors (N, size), action masks (N, 9) and due agents (N,) into
    `out`'s first three arrays (`ArrayStep`'s order), of the round `r` (`RoundState.kernel`),
    the encoder's arrays in `e` (`kernel_arrays`' names) and `bomb`
    (bomb state, carrier, bomb position, `round_inputs`): each agent's own entries, its teammate
    and enemy slots and the bomb's offset at `e.starts` (`_PER_AGENT`), the round's entries at
    `e.bomb_starts` (`_BOMB`) from the round inputs (`ROUND_INPUTS`) and the tick: the round's
    time left counts to the plant once there is one, the bomb's while it is planted."""
    obs, masks, due = out[0], out[1], out[2]
    bomb_state, carrier, bomb_pos, round_inputs = bomb
    # the fields read per agent, taken out of the structs once
    pos, yaw, hp, alive, waiting = r.position, r.yaw, r.hp, r.alive, r.waiting
    armor, helmet, kit, node, out_edges = r.armor, r.helmet, r.has_defuser, r.node, r.out_edges
    hold_until = r.hold_until
    mates, enemies, half, centre, is_ct = e.mates, e.enemies, e.half, e.centre, e.is_ct
    n = pos.shape[0]
    obs[:] = 0.0
    masks[:] = 0
    p0, y0, h0, a0, hel0, k0, b0, c0, d0, m0, e0, o0 = e.starts
    state0, site0, plant0, defuse0, round0, timer0 = e.bomb_starts
    site = np.int64(round_inputs[0])
    planted_tick, round_ticks, bomb_ticks = round_inputs[3], round_inputs[5], round_inputs[6]
    clock = planted_tick if planted_tick >= 0 else tick
    round_left = min(1.0, max(0.0, (round_ticks - clock) / round_ticks))
    bomb_left = 0.0
    if round_inputs[4]:
        bomb_left = min(1.0, max(0.0, (planted_tick + bomb_ticks - tick) / bomb_ticks))
    for i in range(n):
        due[i] = not done and is_due(i, waiting, alive, hold_until, tick + 1)
        masks[i, out_edges.shape[1]] = 1  # STOP
        if due[i]:
            for action in range(out_edges.shape[1]):
                masks[i, action] = 1 if out_edges[node[i], action] >= 0 else 0
        for axis in range(3):
            v = (pos[i, axis] - centre[axis]) / half[axis]
            obs[i, p0 + axis] = min(1.0, max(-1.0, v))
        angle = math.radians(yaw[i])
        obs[i, y0], obs[i, y0 + 1] = math.sin(angle), math.cos(angle)
        obs[i, h0] = hp[i] / 100.0
        obs[i, a0] = armor[i] / 100.0
        obs[i, hel0] = 1.0 if helmet[i] else 0.0
        obs[i, k0] = 1.0 if kit[i] else 0.0
        obs[i, b0] = 1.0 if i == carrier else 0.0
        obs[i, c0] = 1.0 if is_ct[i] else 0.0
        obs[i, d0] = 1.0 if due[i] else 0.0
        for start, table in ((m0, mates), (e0, enemies)):
            for slot in range(table.shape[1]):
                j = table[i, slot]
                if j < 0 or not alive[j]:
                    continue  # zeros: an unused slot or a dead agent
                at = start + 5 * slot
                obs[i, at] = 1.0
                for axis in range(3):
                    v = (pos[j, axis] - pos[i, axis]) / (2 * half[axis])
                    obs[i, at + 1 + axis] = min(1.0, max(-1.0, v))
                obs[i, at + 4] = hp[j] / 100.0
        if bomb_state != 0:
            for axis in range(3):
                v = (bomb_pos[axis] - pos[i, axis]) / (2 * half[axis])
                obs[i, o0 + axis] = min(1.0, max(-1.0, v))
        obs[i, state0 + bomb_state] = 1.0
        if site >= 0:
            obs[i, site0 + site] = 1.0
        obs[i, plant0] = round_inputs[1]
        obs[i, defuse0] = round_inputs[2]
        obs[i, round0] = round_left
        obs[i, timer0] = bomb_left
