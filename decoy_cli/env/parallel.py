"""A PettingZoo `ParallelEnv` over the simulator: T against CT on the waypoint graph, one round
per episode.

The game is `DecoyArrayEnv` (array_env.py); this class is PettingZoo's API over it, one
dictionary entry per agent name. Decisions are asynchronous, as in the engine: an agent decides
when it reaches its waypoint or its STOP ends, never in between. `step(actions)` applies the
actions of the agents that need a decision, then advances the simulator tick by tick until at
least one alive agent needs the next one, or the round ends; so one environment step is one tick
or more of game time. The observation tells each agent whether its action will be used
(`needs_decision`), and its action mask then allows only STOP when it will not.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from numbers import Integral
from typing import Any, TypedDict

import gymnasium
import numpy as np
from gymnasium import spaces
from pettingzoo import ParallelEnv

from decoy_cli.env.array_env import DEFAULT_WEAPONS, ArrayStep, DecoyArrayEnv
from decoy_cli.env.observation import NUM_ACTIONS
from decoy_cli.sim.combat import DamageModel
from decoy_cli.sim.engine import Simulator
from decoy_cli.sim.setup import MoverName
from decoy_cli.waypoints.graph import WaypointGraph
from decoy_cli.world.physics import PhysicsWorld
from decoy_cli.world.world import World

__all__ = ["DEFAULT_WEAPONS", "DecoyParallelEnv"]


class RoundEnd(TypedDict, total=False):
    """How the round ended, in every agent's info once it has."""

    winner: str
    reason: str | None


class AgentInfo(RoundEnd):
    """An agent's info: whether it needs a decision, the tick, and the round's end once over."""

    needs_decision: bool
    tick: int


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
        mover: MoverName = "kinematic",
        damage_model: DamageModel | Callable[[], DamageModel | None] | None = None,
        combat: bool = True,
        bomb: bool = True,
        stop_seconds: float = 0.5,
        weapons: Mapping[str, str] | None = None,
        render_mode: str | None = None,
    ) -> None:
        if render_mode is not None and render_mode not in self.metadata["render_modes"]:
            raise ValueError(f"unknown render_mode {render_mode!r} (rgb_array or None)")
        self.game = DecoyArrayEnv(
            n_t, n_ct, map, graph, world, mover, damage_model, combat, bomb, stop_seconds, weapons
        )
        """The game under this API: arrays in `possible_agents` order."""
        game = self.game
        self.graph = game.graph
        map_name = str(self.graph.meta.get("map", "")).removeprefix("de_") or "custom"
        self.metadata = {**type(self).metadata, "name": f"decoy_{map_name}_v0"}
        self.world = world
        self.mover_kind = mover
        self.damage_model = game.damage_model
        self.bomb = game.bomb
        self.setup = game.setup
        """How every round of this environment is simulated."""
        self.render_mode = render_mode
        self.n_t, self.n_ct = game.n_t, game.n_ct
        self.stop_ticks = game.stop_ticks
        self.possible_agents = list(game.possible_agents)
        self.agents: list[str] = []
        self.layout = game.encoder.layout
        low, high = game.encoder.bounds()
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
        self._index = {name: k for k, name in enumerate(self.possible_agents)}
        self._due = np.zeros(len(self.possible_agents), dtype=bool)
        self._actions = np.zeros(len(self.possible_agents), dtype=np.int64)

    # ---- PettingZoo API -----------------------------------------------------------------------

    def observation_space(self, agent: str) -> spaces.Dict:
        return self._observation_spaces[agent]

    def action_space(self, agent: str) -> spaces.Discrete:
        return self._action_spaces[agent]

    @property
    def sim(self) -> Simulator | None:
        """The simulator of the current round (None before the first reset or after close)."""
        return self.game.sim

    @property
    def physics(self) -> PhysicsWorld | None:
        """The pybullet client of the current round (None with the kinematic mover and no
        combat, or after `close()`)."""
        return self.game.physics

    def reset(
        self, seed: int | None = None, options: dict[str, object] | None = None
    ) -> tuple[dict[str, dict[str, np.ndarray]], dict[str, AgentInfo]]:
        """Start a new round; `options` is not used."""
        state = self.game.reset(seed)
        self.agents = list(self.possible_agents)
        self._due = state.needs_decision
        return self._observe(self.agents, state), self._infos(self.agents, state)

    def step(
        self, actions: Mapping[str, object]
    ) -> tuple[
        dict[str, dict[str, np.ndarray]],
        dict[str, float],
        dict[str, bool],
        dict[str, bool],
        dict[str, AgentInfo],
    ]:
        """Apply the actions of the agents that need a decision, then run the simulator until
        an alive agent needs one or the round ends."""
        if self.game.sim is None:
            raise RuntimeError("call reset() before step() or render()")
        unknown = sorted(set(actions) - set(self.agents))
        if unknown:
            raise ValueError(f"actions for agents not in the episode: {', '.join(unknown)}")
        live = self.agents
        if not live:
            return {}, {}, {}, {}, {}
        chosen = self._actions
        chosen[:] = 0
        for agent in np.flatnonzero(self._due).tolist():
            name = self.possible_agents[agent]
            if name not in actions:
                raise ValueError(f"agent {name} needs a decision but was given no action")
            chosen[agent] = self._action(agent, actions[name])
        state = self.game.step(chosen)
        self._due = state.needs_decision
        index = self._index
        reward, ended, active = (
            a.tolist() for a in (state.rewards, state.terminated, state.active)
        )
        rewards = {name: reward[index[name]] for name in live}
        terminations = {name: ended[index[name]] for name in live}
        truncations = dict.fromkeys(live, False)
        observations = self._observe(live, state)
        infos = self._infos(live, state)
        self.agents = [name for name in live if active[index[name]]]
        return observations, rewards, terminations, truncations, infos

    def render(self) -> np.ndarray | None:
        """A top-down RGB picture (H, W, 3) uint8 of the round with render_mode "rgb_array"."""
        if self.render_mode is None:
            gymnasium.logger.warn("render() without a render_mode: pass render_mode='rgb_array'")
            return None
        return self.game.render()

    def close(self) -> None:
        """Disconnect the pybullet client and drop the round; safe to call more than once."""
        self.game.close()
        self.agents = []

    # ---- internals ----------------------------------------------------------------------------

    def _action(self, agent: int, action: object) -> int:
        """An agent's action as the int 0..8 it must be (8: STOP)."""
        if isinstance(action, bool) or not isinstance(action, Integral):
            raise ValueError(
                f"{self.possible_agents[agent]}: an action is an int 0..8, got {action!r}"
            )
        if not 0 <= int(action) < NUM_ACTIONS:
            raise ValueError(f"{self.possible_agents[agent]}: action {action} is not in 0..8")
        return int(action)

    def _observe(self, names: list[str], state: ArrayStep) -> dict[str, dict[str, np.ndarray]]:
        vectors, masks, index = state.observations, state.action_masks, self._index
        return {
            name: {"observation": vectors[k], "action_mask": masks[k]}
            for name in names
            for k in (index[name],)
        }

    def _infos(self, names: list[str], state: ArrayStep) -> dict[str, AgentInfo]:
        end: RoundEnd = {}
        if state.winner is not None:
            end = {"winner": state.winner, "reason": state.reason}
        due, index, tick = state.needs_decision.tolist(), self._index, state.tick
        return {name: {"needs_decision": due[index[name]], "tick": tick, **end} for name in names}
