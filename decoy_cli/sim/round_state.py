"""The round's state as the engine and compiled code share it: one `RoundState`.

`RoundState` is built once when a simulator opens its round (`Simulator.state`). It owns the
engine's decision arrays (who waits, STOPs, wants to plant or defuse, walks to which node, is on
a damaging drop) and holds the round's other owners: the agents (`Agents`, whose arrays are the
agents' state), the mover (its packed slots) and the waypoint graph. No array has a second
Python handle: the agents' position is `agents.position`, nowhere else.

It goes to compiled code as ONE argument, a numba struct (`structref`) built once (`kernel`):
the very arrays of those owners, not copies, under their owners' names (`ROUND_FIELDS`), so what
compiled code writes the engine, the agents and the mover see. Numba's dispatch checks and
converts every argument of every call, a struct costs one, and a kernel reads its fields by name
instead of taking dozens of positional arrays. With numba's JIT disabled (kernels run as Python)
the struct is a plain namespace of the same fields.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
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
    """The round's arrays as one numba struct (fields: `ROUND_FIELDS`, in that order)."""


def pack(make: Callable[..., object], names: Sequence[str], values: Sequence[object]) -> object:
    """The numba struct `make` builds of `values` (named `names`), or a plain namespace of them
    where numba's JIT is disabled."""
    if jit_enabled():
        return make(*values)
    return SimpleNamespace(**dict(zip(names, values, strict=True)))


AGENT_FIELDS = ("position", "yaw", "hp", "armor", "helmet", "has_defuser", "alive", "node")
"""The agents' arrays compiled code reads and writes (`Agents`' fields of those names)."""
DECISION_FIELDS = (
    "waiting", "hold_until", "decisions", "wants_plant", "wants_defuse", "goal_node", "fall_m",
)  # fmt: skip
"""`RoundState`'s own arrays."""
MOVER_FIELDS = ("mpos", "start", "target", "fv", "iv", "flags", "prm", "jump_speed", "gravity")
"""The mover's packed slots (`MoverBase.kernel_arrays`; `movement.layout` names them), then its
jump speed and gravity."""
GRAPH_FIELDS = (
    "first", "actions", "out_edges", "edge_target", "edge_kind", "edge_fall", "node_pos",
)  # fmt: skip
"""The graph's arrays, read only: each node's possible actions (`first`, `actions`:
`WaypointGraph.allowed_actions`), its edges, `WaypointGraph.fall_m` and `.positions`."""
ROUND_FIELDS = AGENT_FIELDS + DECISION_FIELDS + MOVER_FIELDS + GRAPH_FIELDS
"""`RoundStruct`'s fields, in order."""

structref.define_proxy(RoundStruct, _RoundType, list(ROUND_FIELDS))


@dataclass(slots=True)
class RoundState:
    """One round's decision arrays (N rows each) beside the agents, the mover and the graph
    they decide on; `kernel` is all their arrays as one struct for compiled code (module
    docstring)."""

    agents: Agents
    mover: MoverBase
    graph: WaypointGraph
    waiting: np.ndarray  # bool: asks for a decision at the next tick
    hold_until: np.ndarray  # int64: end tick of a STOP (0: none)
    decisions: np.ndarray  # int64: decisions made
    wants_plant: np.ndarray  # bool
    wants_defuse: np.ndarray  # bool
    goal_node: np.ndarray  # int64: the node the agent walks to (-1: none)
    fall_m: np.ndarray  # float64: depth of the damaging drop it is on (0: none)
    kernel: object = field(init=False, repr=False)

    def __post_init__(self) -> None:
        agents, mover, graph = self.agents, self.mover, self.graph
        values = [getattr(agents, name) for name in AGENT_FIELDS]
        values += [getattr(self, name) for name in DECISION_FIELDS]
        values += [*mover.kernel_arrays(), mover.jump_speed, mover.gravity]
        values += [*graph.allowed_actions, graph.out_edges, graph.edge_target, graph.edge_kind]
        values += [graph.fall_m, graph.positions]
        self.kernel = pack(_round_struct, ROUND_FIELDS, values)

    def due(self, tick: int) -> np.ndarray:
        """Indices (ascending) of the agents due for a decision at `tick` (`schedule`)."""
        return due_agents(self.waiting, self.agents.alive, self.hold_until, tick)

    def next_due(self, tick: int) -> int:
        """The first tick after `tick` at which an agent is due for a decision, if no agent
        arrives before (`schedule`)."""
        return next_due(self.waiting, self.agents.alive, self.hold_until, tick)

    @classmethod
    def open(cls, agents: Agents, mover: MoverBase, graph: WaypointGraph) -> RoundState:
        """The state of a round of `agents` moved by `mover` (already reset to them) on `graph`:
        the decision arrays new, everyone waiting for a first decision."""
        n = agents.count
        return cls(
            agents, mover, graph, np.ones(n, bool), np.zeros(n, np.int64), np.zeros(n, np.int64),
            np.zeros(n, bool), np.zeros(n, bool), np.full(n, -1, np.int64), np.zeros(n),
        )  # fmt: skip


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
