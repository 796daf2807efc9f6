"""The round's state, one owner for the engine and compiled code: one `RoundState`.

`RoundState` is built once when a simulator opens its round (`Simulator.state`). It holds the
agents' arrays (under `Agents`' names), the decision arrays (which it allocates and owns), the
mover's packed slots and what decisions read of the waypoint graph: the very arrays, not copies,
so what compiled code writes the engine, the agents and the mover see.

It goes to compiled code as ONE argument, a numba struct (`structref`) built once (`kernel`):
numba's dispatch checks and converts every argument of every call, a struct costs one, and a
kernel reads its fields by name instead of taking dozens of positional arrays. With numba's JIT
disabled (kernels run as Python) the struct is a plain namespace of the same fields.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass, field, fields
from types import SimpleNamespace

import numpy as np
from numba.core import types
from numba.experimental import structref

from decoy_cli.compiled import jit_enabled, njit_cached
from decoy_cli.sim.movement.base import MoverBase
from decoy_cli.sim.movement.layout import F_HEADING, R_ARRIVED, R_MOVED
from decoy_cli.sim.schedule import due_agents, next_due
from decoy_cli.sim.state import Agents
from decoy_cli.waypoints.graph import WaypointGraph


class StructBase(types.StructRef):
    """A numba struct type whose fields take the types of the values first put in (an int
    field is an int, not the literal it was made with)."""

    def preprocess_fields(self, fields: tuple) -> tuple:
        return tuple((name, types.unliteral(kind)) for name, kind in fields)


@structref.register
class _RoundType(StructBase):
    pass


class RoundStruct(structref.StructRefProxy):
    """`RoundState`'s arrays as one numba struct (fields: `RoundState`'s, in its order)."""


def pack(make: Callable[..., object], names: Sequence[str], values: Sequence[object]) -> object:
    """The numba struct `make` builds of `values` (named `names`), or a plain namespace of them
    where numba's JIT is disabled."""
    if jit_enabled():
        return make(*values)
    return SimpleNamespace(**dict(zip(names, values, strict=True)))


@dataclass(slots=True)
class RoundState:
    """One round's per-agent arrays (N rows each), as the engine, the agents and the mover share
    them, and its graph's; `kernel` is the same arrays as one struct for compiled code (module
    docstring)."""

    # the agents' (`Agents`, under its names)
    position: np.ndarray  # (N, 3) float64, feet
    yaw: np.ndarray  # float64, degrees
    hp: np.ndarray  # int16
    armor: np.ndarray  # int16
    helmet: np.ndarray  # bool
    has_defuser: np.ndarray  # bool: has a defuse kit
    alive: np.ndarray  # bool
    node: np.ndarray  # int64: the waypoint last reached
    # the engine's decisions
    waiting: np.ndarray  # bool: asks for a decision at the next tick
    hold_until: np.ndarray  # int64: end tick of a STOP (0: none)
    decisions: np.ndarray  # int64: decisions made
    wants_plant: np.ndarray  # bool
    wants_defuse: np.ndarray  # bool
    goal_node: np.ndarray  # int64: the node the agent walks to (-1: none)
    fall_m: np.ndarray  # float64: depth of the damaging drop it is on (0: none)
    # the mover's packed slots (`MoverBase.kernel_arrays`; `movement.layout` names them)
    mpos: np.ndarray  # (N, 3) the mover's positions
    start: np.ndarray
    target: np.ndarray
    fv: np.ndarray
    iv: np.ndarray
    flags: np.ndarray
    prm: np.ndarray
    jump_speed: float
    gravity: float
    # the graph's (`WaypointGraph`), read only
    first: np.ndarray  # (nodes + 1,) and ...
    actions: np.ndarray  # ... each node's possible actions (`WaypointGraph.allowed_actions`)
    out_edges: np.ndarray  # (nodes, 8) int64
    edge_target: np.ndarray
    edge_kind: np.ndarray
    edge_fall: np.ndarray  # `WaypointGraph.fall_m`
    node_pos: np.ndarray  # (nodes, 3) `WaypointGraph.positions`
    kernel: object = field(init=False, repr=False)

    def __post_init__(self) -> None:
        self.kernel = pack(_round_struct, ROUND_FIELDS, [getattr(self, n) for n in ROUND_FIELDS])

    def due(self, tick: int) -> np.ndarray:
        """Indices (ascending) of the agents due for a decision at `tick` (`schedule`)."""
        return due_agents(self.waiting, self.alive, self.hold_until, tick)

    def next_due(self, tick: int) -> int:
        """The first tick after `tick` at which an agent is due for a decision, if no agent
        arrives before (`schedule`)."""
        return next_due(self.waiting, self.alive, self.hold_until, tick)

    @classmethod
    def open(cls, agents: Agents, mover: MoverBase, graph: WaypointGraph) -> RoundState:
        """The state of a round of `agents` moved by `mover` (already reset to them) on `graph`:
        the engine's decision arrays new, everyone waiting for a first decision."""
        n = agents.count
        mpos, start, target, fv, iv, flags, prm = mover.kernel_arrays()
        first, actions = graph.allowed_actions
        return cls(
            agents.position, agents.yaw, agents.hp, agents.armor, agents.helmet,
            agents.has_defuser, agents.alive, agents.node,
            np.ones(n, bool), np.zeros(n, np.int64), np.zeros(n, np.int64), np.zeros(n, bool),
            np.zeros(n, bool), np.full(n, -1, np.int64), np.zeros(n),
            mpos, start, target, fv, iv, flags, prm, mover.jump_speed, mover.gravity,
            first, actions, graph.out_edges, graph.edge_target, graph.edge_kind, graph.fall_m,
            graph.positions,
        )  # fmt: skip


ROUND_FIELDS = tuple(f.name for f in fields(RoundState) if f.name != "kernel")
"""`RoundStruct`'s fields, in order."""

structref.define_proxy(RoundStruct, _RoundType, list(ROUND_FIELDS))


@njit_cached
def _round_struct(*values):
    """A `RoundStruct` made in compiled code, so that its constructor is cached with it."""
    return RoundStruct(*values)


@njit_cached
def take_motion(r):
    """Take over what the mover's last call did (`r`: `RoundState.kernel`): the agents stand
    where the mover has them, those that moved face their heading, and the alive ones that
    arrived stand on their goal node and wait for a decision. The one place both the engine
    (`Simulator._moved`) and the compiled stretches (`quiet_play.play_quiet`) take motion over."""
    r.position[:] = r.mpos
    flags, yaw, fv, alive, node, goal_node = r.flags, r.yaw, r.fv, r.alive, r.node, r.goal_node
    for i in range(yaw.shape[0]):
        if flags[R_MOVED, i]:
            yaw[i] = fv[i, F_HEADING]
        if flags[R_ARRIVED, i] and alive[i]:
            node[i] = goal_node[i]
            goal_node[i] = -1
            r.waiting[i] = True
