"""A PettingZoo `ParallelEnv` over the simulator: T against CT on the waypoint graph, one round
per episode.

Decisions are asynchronous, as in the engine: an agent decides when it reaches its waypoint or
its STOP ends, never in between. `step(actions)` applies the actions of the agents that need a
decision, then advances the simulator tick by tick until at least one alive agent needs the
next one, or the round ends; so one environment step is one tick or more of game time. The
observation tells each agent whether its action will be used (`needs_decision`), and its action
mask then allows only STOP when it will not.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from contextlib import ExitStack
from numbers import Integral
from typing import Any, TypeGuard, cast

import gymnasium
import numpy as np
from gymnasium import spaces
from pettingzoo import ParallelEnv

from decoy_cli.csgo import BUILTIN_MAP, seconds_to_ticks
from decoy_cli.errors import GraphError
from decoy_cli.sim.combat import DamageModel
from decoy_cli.sim.decisions import Decision
from decoy_cli.sim.engine import Simulator
from decoy_cli.sim.observation import (
    NUM_ACTIONS,
    ObservationEncoder,
)
from decoy_cli.sim.quiet_play import Choices, play_stretch
from decoy_cli.sim.rules import RulesConfig
from decoy_cli.sim.setup import RoundSetup, open_round
from decoy_cli.sim.state import Agents
from decoy_cli.sim.view import TopDownView
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
    (a T) or defuses (a CT). With the kinematic mover the step's quiet stretches are played in
    compiled code (`quiet_play`) up to the next tick at which an agent is due."""

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

    def play_quiet(
        self, sim: Simulator, horizon: int, max_decisions: int, watch: np.ndarray
    ) -> int:
        """The step's quiet stretches in compiled code (`quiet_play.play_stretch`); a tick with
        an impossible move is left to Python, which stands the agent still and records it."""
        return play_stretch(sim, horizon, max_decisions, watch, self.choices)


def _map_graph(map_name: str | None, graph: WaypointGraph | None) -> WaypointGraph:
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


class DecoyParallelEnv(ParallelEnv):
    """One CS:GO round on the waypoint graph as a PettingZoo parallel environment.

    Map: `map` names a built-in map ("mirage" or "de_mirage"; default de_dust2), whose shipped
    graph and world are used; a `graph` given instead is used as it is (`map`, if also given,
    must be the graph's map).

    Agents: `t_0 .. t_{n_t-1}` then `ct_0 .. ct_{n_ct-1}`, spawned at distinct random waypoints
    of the graph regions `t_spawn` and `ct_spawn`, 100 HP, no armor, the side's pistol (or
    `weapons`, keyed by side "T"/"CT" or by agent name, agent names first). With `bomb`, a
    random T carries the bomb.

    Actions: Discrete(9). 0..7 move along the out-edge of the agent's waypoint in compass
    direction N, NE, E, SE, S, SW, W, NW (N = +y, E = +x) at the weapon's full speed; the agent
    decides again when it reaches the next waypoint. 8 is STOP: stand still for `stop_seconds`
    (whole ticks, rounded up; 0.5 s = 30 ticks), then decide again. STOP is also the objective
    action: a T carrying the bomb inside a bomb-site zone plants while it stands (the rules'
    plant time, so several STOPs in a row), a CT in range of the planted bomb defuses. A move
    with no edge in its direction (masked out) stands still like a STOP, without planting or
    defusing, and the engine records an "invalid_action" event.

    Asynchronous decisions: only agents with `needs_decision` (observation entry and info) have
    their action applied; the action of any other agent is ignored (it is walking an edge or
    holding a STOP) and its mask allows only STOP. `step` then runs the simulator until an
    alive agent needs a decision or the round ends. An agent that needs a decision must get an
    action (a ValueError otherwise); the others may be left out.

    Observation: {"observation": float32 vector, "action_mask": int8 (9,)}, one length for every
    agent. With S = max(n_t, n_ct) slots, the vector holds, in this order
    (`observation_layout` gives the slices; `env.layout` those of this environment):

    * position (3): own feet x, y, z, normalised to [-1, 1] by the waypoints' bounding box
      grown by `POSITION_MARGIN_M` on every side (clipped);
    * yaw (2): sin and cos of the own view yaw (0 = east, counter-clockwise);
    * hp, armor (1 each): /100;
    * helmet, defuse_kit, has_bomb, is_ct, needs_decision (1 each): 0 or 1;
    * teammates (S-1 slots x 5): the other agents of the own side in index order (t_1, t_2...
      for t_0): alive, offset x, y, z from the own feet divided by the grown box's size
      (in [-1, 1], clipped), hp/100; all zeros for a dead teammate or an unused slot;
    * enemies (S slots x 5): the agents of the other side in index order, same features;
    * bomb_state (6): one-hot none, carried, dropped, planted, defused, exploded;
    * bomb_offset (3): the bomb (its carrier while carried) from the own feet, scaled as the
      slot offsets; zeros when there is no bomb;
    * bomb_site (2): one-hot A, B once planted;
    * plant_progress, defuse_progress (1 each): the fraction done of a plant or defuse under
      way, else 0;
    * round_time_left (1): of the 115 s round, frozen at the plant (a plant stops the clock);
    * bomb_time_left (1): of the 40 s bomb timer while the bomb is planted, else 0.

    Positions of all agents are visible to all (no fog of war). Length 12 + 10 S - 5 + 15:
    72 for 5 against 5.

    Action mask: 1 for each move with an out-edge at the agent's waypoint and for STOP, when the
    agent needs a decision; otherwise only STOP.

    Rewards: 0 during the round; at its end +1 to every agent of the winning side and -1 to the
    losing side (agents still in the episode: one that died earlier left with 0). Terminations:
    an agent that dies terminates (and leaves `self.agents`); at the round end every agent
    does. Truncations are always False: the rules end every round within the engine's bound
    (115 s, or the plant plus 40 s). Infos: "needs_decision" and "tick" (simulator tick of the
    state) for every agent, plus "winner" and "reason" (ESTA names) at the round end.

    Seeding: `reset(seed=...)` seeds a numpy Generator that draws the spawns, the bomb carrier
    and the simulator's seed (combat randomness); `reset()` without a seed continues it. The
    same seed and actions give the same round with either mover.

    Combat: `damage_model` is a `DamageModel` (decoy_cli/sim/combat.py), or a function that
    loads one (called once, here), e.g. `lambda: load_damage_model("shipped")` with
    `decoy_cli.damage.load_damage_model` ("shipped", "rules", "none" or the path of a model
    folder such as `decoy models import-decoy` writes). None: no combat, and agents never die.
    `combat` False keeps the model but turns shooting off; `bomb` False takes the bomb out of the
    round.

    pybullet: the physics mover and combat (`damage_model`) need a pybullet client with the
    world (`world`, default the built-in nav world); it is created at the first reset that
    needs it and serves every later round (each round removes its own bodies at its end), and
    `close()` disconnects it. Rounds are set up
    by `decoy_cli.sim.setup.open_round`, as every other user of the simulator does.

    Rendering: `render_mode="rgb_array"` gives a top-down matplotlib picture (waypoints grey,
    T orange, CT blue, dead agents light grey, the bomb a red star).
    """

    metadata: dict[str, Any] = {"name": "decoy_v0", "render_modes": ["rgb_array"]}  # noqa: RUF012
    """Each environment's own copy names its map: "decoy_dust2_v0", "decoy_mirage_v0", ..."""

    def __init__(
        self,
        n_t: int = 5,
        n_ct: int = 5,
        map: str | None = None,
        graph: WaypointGraph | None = None,
        world: World | None = None,
        mover: str = "kinematic",
        damage_model: DamageModel | Callable[[], DamageModel | None] | None = None,
        combat: bool = True,
        bomb: bool = True,
        stop_seconds: float = 0.5,
        weapons: Mapping[str, str] | None = None,
        render_mode: str | None = None,
    ) -> None:
        for name, count in (("n_t", n_t), ("n_ct", n_ct)):
            if isinstance(count, bool) or not isinstance(count, Integral) or count < 0:
                raise ValueError(f"{name} must be an int >= 0, got {count!r}")
        if n_t + n_ct == 0:
            raise ValueError("a round needs at least one agent")
        if not stop_seconds > 0:
            raise ValueError(f"stop_seconds must be > 0, got {stop_seconds!r}")
        if render_mode is not None and render_mode not in self.metadata["render_modes"]:
            raise ValueError(f"unknown render_mode {render_mode!r} (rgb_array or None)")
        self.graph = _map_graph(map, graph)
        map_name = str(self.graph.meta.get("map", "")).removeprefix("de_") or "custom"
        self.metadata = {**type(self).metadata, "name": f"decoy_{map_name}_v0"}
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
        self.render_mode = render_mode
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
        self.agents: list[str] = []
        self._index = {name: k for k, name in enumerate(self.possible_agents)}
        self._sides = ["T"] * n_t + ["CT"] * n_ct
        self._weapons = self._weapon_list(weapons or {})
        self._rules_config: RulesConfig = self.setup.rules_config()

        self._encoder = ObservationEncoder(self.graph, self._sides, self._rules_config, self.bomb)
        self.layout = self._encoder.layout
        low, high = self._encoder.bounds()
        self._observation_spaces = {
            agent: spaces.Dict(
                {
                    "observation": spaces.Box(low, high, dtype=np.float32),
                    "action_mask": spaces.Box(0, 1, (NUM_ACTIONS,), np.int8),
                }
            )
            for agent in self.possible_agents
        }
        self._action_spaces: dict[str, spaces.Discrete] = {
            agent: spaces.Discrete(NUM_ACTIONS) for agent in self.possible_agents
        }

        self._rng: np.random.Generator | None = None
        self._sim: Simulator | None = None
        self._policy = _ChosenActions(self._sides, self.stop_ticks)
        self._due_next = np.zeros(len(self._sides), dtype=bool)  # who decides at the next step
        self.physics: PhysicsWorld | None = None
        """The pybullet client of the current round (None with the kinematic mover and no
        combat, or after `close()`)."""
        self._round = ExitStack()
        self._world = ExitStack()  # the pybullet client, kept across rounds
        self._view: TopDownView | None = None

    # ---- PettingZoo API -----------------------------------------------------------------------

    def observation_space(self, agent: str) -> spaces.Dict:
        return self._observation_spaces[agent]

    def action_space(self, agent: str) -> spaces.Discrete:
        return self._action_spaces[agent]

    @property
    def sim(self) -> Simulator | None:
        """The simulator of the current round (None before the first reset or after close)."""
        return self._sim

    def reset(
        self, seed: int | None = None, options: dict[str, Any] | None = None
    ) -> tuple[dict[str, dict[str, np.ndarray]], dict[str, dict[str, Any]]]:
        """Start a new round; `options` is not used."""
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
            sides=self._sides,
            positions=self.graph.positions[nodes],
            nodes=nodes,
            weapons=self._weapons,
        )
        carrier = int(rng.integers(self.n_t)) if self.bomb and self.n_t else -1
        self._end_round()
        self._policy = _ChosenActions(self._sides, self.stop_ticks)
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
        self.agents = list(self.possible_agents)
        due = self._due_next = self._sim.needs_decision
        return self._observe(self.agents, due), self._infos(self.agents, due)

    def step(
        self, actions: Mapping[str, Any]
    ) -> tuple[
        dict[str, dict[str, np.ndarray]],
        dict[str, float],
        dict[str, bool],
        dict[str, bool],
        dict[str, dict[str, Any]],
    ]:
        """Apply the actions of the agents that need a decision, then run the simulator until
        an alive agent needs one or the round ends."""
        sim = self._require_sim()
        unknown = sorted(set(actions) - set(self.agents))
        if unknown:
            raise ValueError(f"actions for agents not in the episode: {', '.join(unknown)}")
        live = list(self.agents)
        due = self._due_next
        given = self._policy.choices.given
        given[:] = -1
        for name in live:
            agent = self._index[name]
            if due[agent]:
                if name not in actions:
                    raise ValueError(f"agent {name} needs a decision but was given no action")
                given[agent] = self._action(agent, actions[name])
        sim.run(stop_when_due=True)  # the first tick takes the decisions, then on to the next
        if np.any(given >= 0):
            raise RuntimeError(
                f"the simulator did not ask agents {np.flatnonzero(given >= 0).tolist()} for "
                "the decision the environment collected"
            )

        outcome = sim.outcome
        alive = sim.agents.alive
        rewards = dict.fromkeys(live, 0.0)
        if outcome is not None:
            for name in live:
                rewards[name] = 1.0 if self._sides[self._index[name]] == outcome.winner else -1.0
        terminations = {
            name: bool(outcome is not None or not alive[self._index[name]]) for name in live
        }
        truncations = dict.fromkeys(live, False)
        due = self._due_next = sim.needs_decision
        observations = self._observe(live, due)
        infos = self._infos(live, due)
        self.agents = [name for name in live if not terminations[name]]
        return observations, rewards, terminations, truncations, infos

    def render(self) -> np.ndarray | None:
        """A top-down RGB picture (H, W, 3) uint8 of the round with render_mode "rgb_array"."""
        if self.render_mode is None:
            gymnasium.logger.warn("render() without a render_mode: pass render_mode='rgb_array'")
            return None
        sim = self._require_sim()
        if self._view is None:
            self._view = TopDownView(self.graph, self._sides)
        return self._view.draw(sim.agents, sim.bomb if self.bomb else None)

    def close(self) -> None:
        """Disconnect the pybullet client and drop the round; safe to call more than once."""
        self._end_round()
        self._world.close()
        self._world = ExitStack()
        self.physics = None
        self.agents = []
        self._view = None

    # ---- internals ----------------------------------------------------------------------------

    def _require_sim(self) -> Simulator:
        if self._sim is None:
            raise RuntimeError("call reset() before step() or render()")
        return self._sim

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
            for name, side in zip(self.possible_agents, self._sides, strict=True)
        ]

    def _end_round(self) -> None:
        """Release the current round's bodies (the pybullet client stays for the next)."""
        self._round.close()
        self._round = ExitStack()
        self._sim = None

    def _action(self, agent: int, action: Any) -> int:
        """An agent's action as the int 0..8 it must be (8: STOP)."""
        if isinstance(action, bool) or not isinstance(action, Integral):
            raise ValueError(
                f"{self.possible_agents[agent]}: an action is an int 0..8, got {action!r}"
            )
        if not 0 <= int(action) < NUM_ACTIONS:
            raise ValueError(f"{self.possible_agents[agent]}: action {action} is not in 0..8")
        return int(action)

    def _observe(self, names: list[str], due: np.ndarray) -> dict[str, dict[str, np.ndarray]]:
        sim = self._require_sim()
        vectors, masks = self._encoder.encode(sim, due)
        return {
            name: {"observation": vectors[k], "action_mask": masks[k]}
            for name in names
            for k in (self._index[name],)
        }

    def _infos(self, names: list[str], due: np.ndarray) -> dict[str, dict[str, Any]]:
        sim = self._require_sim()
        end = {}
        if sim.outcome is not None:
            end = {"winner": sim.outcome.winner, "reason": sim.outcome.reason}
        return {
            name: {"needs_decision": bool(due[self._index[name]]), "tick": sim.tick, **end}
            for name in names
        }


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
