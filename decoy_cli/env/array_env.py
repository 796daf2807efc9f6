"""The environment's game: one CS:GO round per episode, T against CT on the waypoint graph, every
agent's observation, mask and reward as one array per step.

`DecoyArrayEnv` is the game; `DecoyParallelEnv` (env.py) is the PettingZoo API over it, one
dictionary entry per agent. A trainer that batches its agents (one policy call for all ten)
can use this one directly and skip building and reading the dictionaries; both play the same
rounds from the same seed and actions.

Decisions are asynchronous, as in the engine: an agent decides when it reaches its waypoint or
its STOP ends, never in between. `step(actions)` applies the actions of the agents that need a
decision, then advances the simulator until an alive agent needs the next one, or the round
ends; so one step is one tick or more of game time. `DecoyParallelEnv` documents the actions,
the observation vector and the rewards.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from contextlib import ExitStack
from numbers import Integral
from typing import TypeGuard, cast

import numpy as np

from decoy_cli.csgo import BUILTIN_MAP, seconds_to_ticks
from decoy_cli.env.observation import ObservationEncoder
from decoy_cli.env.step import ArrayStep, RoundSteps
from decoy_cli.env.viewer import TopDownView
from decoy_cli.errors import GraphError
from decoy_cli.sim.combat import DamageModel
from decoy_cli.sim.decisions import Decision
from decoy_cli.sim.engine import Simulator
from decoy_cli.sim.quiet_play import Choices
from decoy_cli.sim.setup import MoverName, RoundSetup, open_round
from decoy_cli.sim.state import Agents
from decoy_cli.waypoints.build import builtin_graph, canonical_map
from decoy_cli.waypoints.graph import WaypointGraph
from decoy_cli.weapons import is_known
from decoy_cli.world.physics import PhysicsWorld
from decoy_cli.world.world import World

DEFAULT_WEAPONS = {"T": "Glock-18", "CT": "USP-S"}
"""The pistol each side starts a pistol round with."""


class _ChosenActions:
    """The engine's policy inside the environment: the actions `step` collected, one per agent
    the engine asks at the step's first tick (-1: none). A STOP holds `stop_ticks` and plants
    (a T) or defuses (a CT). The step's quiet stretches take them in compiled code
    (`env_step`), a tick played by `Simulator.step` through `decide`."""

    def __init__(self, sides: list[str], stop_ticks: int) -> None:
        is_t = np.array([side == "T" for side in sides])
        n = len(sides)
        self.choices = Choices(np.full(n, -1, np.int64), np.zeros(0), 0, stop_ticks, is_t, ~is_t)

    def decide(self, sim: Simulator, agent: int) -> Decision:
        action = int(self.choices.given[agent])
        if action < 0:
            raise RuntimeError(
                f"the simulator asked agent {agent} for a decision at tick {sim.tick}, "
                "which the environment did not expect"
            )
        self.choices.given[agent] = -1
        return self.choices.decision(agent, action)


def map_graph(map_name: str | None, graph: WaypointGraph | None) -> WaypointGraph:
    """The graph of an environment: the given one (which must be of `map_name` when both are
    given) or the built-in graph of `map_name` (default de_dust2)."""
    try:
        map_id = canonical_map(map_name or BUILTIN_MAP)
    except GraphError as error:
        raise ValueError(str(error)) from None
    if graph is None:
        return builtin_graph(map_id)
    graph_map = str(graph.meta.get("map", ""))
    if map_name is not None and graph_map and graph_map != map_id:
        raise ValueError(f"map {map_name!r} given with a graph of {graph_map}")
    return graph


class DecoyArrayEnv:
    """One CS:GO round per episode, every agent's state as one row of an array.

    The arguments and the game (agents, actions, observations, rewards, seeding, combat,
    pybullet, rendering) are those of `DecoyParallelEnv`, which is this environment seen through
    PettingZoo's dictionaries. `reset` and `step` return an `ArrayStep`. `step` takes (N,)
    integer actions in `possible_agents` order: the entry of every agent that needs a decision
    must be 0..8; the others are ignored (any value).
    """

    def __init__(
        self,
        n_t: int = 5,
        n_ct: int = 5,
        map: str | None = None,
        graph: WaypointGraph | None = None,
        world: World | None = None,
        mover: MoverName = "kinematic",
        damage_model: DamageModel | Callable[[], DamageModel | None] | None = None,
        combat: bool = True,
        bomb: bool = True,
        stop_seconds: float = 0.5,
        weapons: Mapping[str, str] | None = None,
    ) -> None:
        for name, count in (("n_t", n_t), ("n_ct", n_ct)):
            if isinstance(count, bool) or not isinstance(count, Integral) or count < 0:
                raise ValueError(f"{name} must be an int >= 0, got {count!r}")
        if n_t + n_ct == 0:
            raise ValueError("a round needs at least one agent")
        if not (math.isfinite(stop_seconds) and seconds_to_ticks(stop_seconds) >= 1):
            raise ValueError(f"stop_seconds must last a tick (1/60 s) or more: {stop_seconds!r}")
        self.graph = map_graph(map, graph)
        self.world = world
        self.mover_kind = mover
        self.damage_model: DamageModel | None
        if _is_loader(damage_model):
            self.damage_model = damage_model()
        else:  # not a loader: a model or None
            self.damage_model = cast("DamageModel | None", damage_model)
        self.bomb = bool(bomb)
        self.setup = RoundSetup(
            graph=self.graph,
            mover=mover,
            combat=combat,
            bomb=self.bomb,
            damage_model=self.damage_model,
            world=world,
        )
        """How every round of this environment is simulated."""
        self.n_t, self.n_ct = int(n_t), int(n_ct)
        self.stop_ticks = seconds_to_ticks(stop_seconds)

        self._t_spawn = self.graph.region_of("t_spawn")
        self._ct_spawn = self.graph.region_of("ct_spawn")
        for side, count, nodes in (("T", n_t, self._t_spawn), ("CT", n_ct, self._ct_spawn)):
            if count > len(nodes):
                raise ValueError(
                    f"{count} {side} agents do not fit the {len(nodes)} spawn waypoints"
                )
        self.possible_agents = [f"t_{k}" for k in range(n_t)] + [f"ct_{k}" for k in range(n_ct)]
        self.sides = ["T"] * n_t + ["CT"] * n_ct
        self._is_t = np.array([side == "T" for side in self.sides])
        self._action_shape = (len(self.sides),)
        self._weapons = self._weapon_list(weapons or {})
        self.encoder = ObservationEncoder(
            self.graph, self.sides, self.setup.rules_config(), self.bomb
        )
        """The observation layout and its bounds (`encoder.layout`, `encoder.bounds()`)."""

        self._rng: np.random.Generator | None = None
        self._sim: Simulator | None = None
        self._steps: RoundSteps | None = None
        self._policy = _ChosenActions(self.sides, self.stop_ticks)
        self.physics: PhysicsWorld | None = None
        """The pybullet client of the current round (None with the kinematic mover and no
        combat, or after `close()`)."""
        self._round = ExitStack()
        self._world = ExitStack()  # the pybullet client, kept across rounds
        self._view: TopDownView | None = None

    @property
    def sim(self) -> Simulator | None:
        """The simulator of the current round (None before the first reset or after close)."""
        return self._sim

    def reset(self, seed: int | None = None) -> ArrayStep:
        """Start a new round: spawns, the bomb carrier and the simulator's seed are drawn from a
        generator `seed` seeds (without a seed, the generator goes on)."""
        if seed is not None or self._rng is None:
            self._rng = np.random.default_rng(seed)
        rng = self._rng
        nodes = np.concatenate(
            [
                rng.choice(self._t_spawn, size=self.n_t, replace=False),
                rng.choice(self._ct_spawn, size=self.n_ct, replace=False),
            ]
        ).astype(np.int64)
        agents = Agents.create(
            names=self.possible_agents,
            sides=self.sides,
            positions=self.graph.positions[nodes],
            nodes=nodes,
            weapons=self._weapons,
        )
        carrier = int(rng.integers(self.n_t)) if self.bomb and self.n_t else -1
        self._end_round()
        self._policy = _ChosenActions(self.sides, self.stop_ticks)
        if self.setup.needs_physics and self.physics is None:
            self.physics = self._world.enter_context(self.setup.open_physics())
        self._sim = self._round.enter_context(
            open_round(
                self.setup,
                agents,
                self._policy,
                physics=self.physics,
                bomb_carrier=carrier,
                seed=int(rng.integers(2**63)),
            )
        )
        self._steps = RoundSteps(
            self._sim, self.encoder, self._policy.choices, self.possible_agents, self._is_t
        )
        return self._steps.state()

    def step(self, actions: np.ndarray) -> ArrayStep:
        """Apply the actions of the agents that need a decision, then run the simulator until
        an alive agent needs one or the round ends. After the round's end, call `reset`."""
        steps = self._require_steps()
        if steps.sim.done:
            raise RuntimeError("the round has ended: call reset() before step()")
        chosen = np.asarray(actions)
        if chosen.shape != self._action_shape or chosen.dtype.kind not in "iu":
            raise ValueError(
                f"actions are ({len(self.sides)},) integers, got {chosen.dtype} {chosen.shape}"
            )
        if chosen.dtype != np.int64 and np.can_cast(chosen.dtype, np.int64):
            chosen = chosen.astype(np.int64)  # one type for the compiled step (uint64 not)
        return steps.play(chosen)

    def render(self) -> np.ndarray:
        """A top-down RGB picture (H, W, 3) uint8 of the round (`TopDownView`)."""
        sim = self._require_sim()
        if self._view is None:
            self._view = TopDownView(self.graph, self.sides)
        return self._view.draw(sim.agents, sim.bomb if self.bomb else None)

    def close(self) -> None:
        """Disconnect the pybullet client and drop the round; safe to call more than once."""
        self._end_round()
        self._world.close()
        self._world = ExitStack()
        self.physics = None
        self._view = None

    # ---- internals ----------------------------------------------------------------------------

    def _require_sim(self) -> Simulator:
        if self._sim is None:
            raise RuntimeError("call reset() before step() or render()")
        return self._sim

    def _require_steps(self) -> RoundSteps:
        if self._steps is None:
            raise RuntimeError("call reset() before step() or render()")
        return self._steps

    def _weapon_list(self, weapons: Mapping[str, str]) -> list[str]:
        """Every agent's weapon: by agent name, else by side, else the side's pistol."""
        unknown_keys = sorted(set(weapons) - {"T", "CT", *self.possible_agents})
        if unknown_keys:
            raise ValueError(
                f"weapons are keyed by side (T, CT) or agent name, got {', '.join(unknown_keys)}"
            )
        bad = sorted(str(w) for w in weapons.values() if not isinstance(w, str) or not is_known(w))
        if bad:
            raise ValueError(f"unknown weapon {bad[0]!r} (use awpy display names like 'AK-47')")
        return [
            weapons.get(name, weapons.get(side, DEFAULT_WEAPONS[side]))
            for name, side in zip(self.possible_agents, self.sides, strict=True)
        ]

    def _end_round(self) -> None:
        """Release the current round's bodies (the pybullet client stays for the next)."""
        self._round.close()
        self._round = ExitStack()
        self._sim = None
        self._steps = None


def _is_loader(value: object) -> TypeGuard[Callable[[], DamageModel | None]]:
    """Whether `value` is a function that loads a damage model rather than a model itself
    (a model is called with a batch and a generator, a loader with nothing)."""
    import inspect

    if value is None or not callable(value):
        return False
    try:
        signature = inspect.signature(value)
    except (TypeError, ValueError):
        return False
    required = [
        p
        for p in signature.parameters.values()
        if p.default is p.empty and p.kind in (p.POSITIONAL_ONLY, p.POSITIONAL_OR_KEYWORD)
    ]
    return not required
