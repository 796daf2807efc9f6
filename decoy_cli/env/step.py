"""The environment's steps of one round: quiet stretches in compiled code, other ticks by
`Simulator.step`, with the result of stepping every tick.

A step plays from the actions handed in to the next tick an alive agent is due (or the round's
end). Most steps of a round with ten agents are quiet: the agents due take their actions,
everybody glides to the next arrival or end of a STOP, and nothing else happens (no combat
step, no recorded tick, no bomb rule, no fall). `_quiet_step` plays such a stretch, and the
step's rewards and observations, in one compiled call; `RoundSteps.play` plays a tick that is
not quiet (a combat step, a plant, a fall) with `Simulator.step` and goes on.

The round's arrays (the simulator's, the mover's, the graph's, the encoder's) go to compiled
code as one `RoundArrays` struct that holds them, not copies: numba's dispatch checks and
converts every argument of every call, and a step is short.

Why a quiet step may skip what `Simulator.run` asks before every stretch: the stretch's
horizon (`Simulator.quiet_horizon`), the agents the bomb rules watch and the round's observation
inputs (`ObservationEncoder.round_inputs`) change only on ticks that are not quiet, so they are
asked after each such tick (or anything else that added an event) and kept while the steps stay
quiet.
"""

from __future__ import annotations

from dataclasses import dataclass
from enum import IntEnum
from types import SimpleNamespace

import numpy as np
from numba.core import types
from numba.experimental import structref

from decoy_cli.compiled import jit_enabled, njit_cached
from decoy_cli.env.observation import NUM_ACTIONS, ObservationEncoder, encode_into
from decoy_cli.sim.engine import Simulator
from decoy_cli.sim.movement.base import MoverBase
from decoy_cli.sim.quiet_play import Choices, StretchEnd, _play, hands_back
from decoy_cli.sim.schedule import NEVER


class StepEnd(IntEnum):
    """How `_quiet_step` ended (none of the last three can happen on a state the environment
    left)."""

    PLAYED = 0
    """It played the step to its end."""
    LEFT_TO_RUN = 1
    """It left the rest of the step to Python (at the stretch's horizon, or at once when an
    action may hand back: a STOP to plant or defuse by an agent the rules watch, a damaging
    drop, a move no edge makes)."""
    BAD_ACTION = 2
    """An action is not 0..8 (nothing was played)."""
    IN_THE_AIR = 3
    """An agent asked to move is in the air."""
    NOT_TAKEN = 4
    """An action handed in was not taken."""
    HALF_PLAYED = 5
    """The stretch handed back with its tick half played."""


# ---- the round's arrays as one struct ---------------------------------------------------------


@structref.register
class _RoundArraysType(types.StructRef):
    def preprocess_fields(self, fields: tuple) -> tuple:
        return tuple((name, types.unliteral(kind)) for name, kind in fields)


class RoundArrays(structref.StructRefProxy):
    """The arrays of one round that compiled steps read and write, held (not copied) in one
    numba struct: `Choices`, graph, agents, simulator, kinematic mover, encoder, and the
    environment's own `due` (whose actions the next step takes) and `active` (in the episode)."""


ROUND_FIELDS = (
    "given", "draws", "first", "actions", "hold_ticks", "plant", "defuse", "top",
    "out_edges", "edge_target", "edge_kind", "edge_fall", "positions",
    "node", "alive", "yaw", "hp", "armor", "helmet", "kit", "pos",
    "waiting", "hold_until", "decisions", "wants_plant", "wants_defuse", "goal_node", "fall_m",
    "mpos", "start", "target", "fv", "iv", "flags", "prm", "jump_speed", "gravity",
    "is_t", "starts", "bomb_starts", "is_ct", "mates", "enemies", "centre", "half",
    "due", "active",
)  # fmt: skip
"""`RoundArrays`' fields in the order `_round_arrays` takes them (`mpos`: the mover's
positions; `pos`: the agents')."""

structref.define_proxy(RoundArrays, _RoundArraysType, list(ROUND_FIELDS))


@njit_cached
def _round_arrays(
    given, draws, first, actions, hold_ticks, plant, defuse, top, out_edges, edge_target,
    edge_kind, edge_fall, positions, node, alive, yaw, hp, armor, helmet, kit, pos, waiting,
    hold_until, decisions, wants_plant, wants_defuse, goal_node, fall_m, mpos, start, target, fv,
    iv, flags, prm, jump_speed, gravity, is_t, starts, bomb_starts, is_ct, mates, enemies,
    centre, half, due, active,
):  # fmt: skip
    """A `RoundArrays` made in compiled code, so that its constructor is cached with it."""
    return RoundArrays(
        given, draws, first, actions, hold_ticks, plant, defuse, top, out_edges, edge_target,
        edge_kind, edge_fall, positions, node, alive, yaw, hp, armor, helmet, kit, pos, waiting,
        hold_until, decisions, wants_plant, wants_defuse, goal_node, fall_m, mpos, start, target,
        fv, iv, flags, prm, jump_speed, gravity, is_t, starts, bomb_starts, is_ct, mates,
        enemies, centre, half, due, active,
    )  # fmt: skip


def _plain_round_arrays(*arrays: object) -> SimpleNamespace:
    """`RoundArrays`' fields on a plain object, for the kernels run as Python (numba's JIT
    disabled), where numba's struct cannot be made."""
    return SimpleNamespace(**dict(zip(ROUND_FIELDS, arrays, strict=True)))


# ---- the steps --------------------------------------------------------------------------------


@dataclass(slots=True)
class ArrayStep:
    """The state after a reset or a step, one row per agent (`possible_agents` order)."""

    observations: np.ndarray  # (N, size) float32 (`DecoyParallelEnv` documents the entries)
    action_masks: np.ndarray  # (N, 9) int8: the moves with an edge and STOP; STOP only if not due
    needs_decision: np.ndarray  # (N,) bool: whose action the next step uses
    rewards: np.ndarray  # (N,) float32: +1/-1 by side at the round's end, else 0
    terminated: np.ndarray  # (N,) bool: left the episode at this step (died, or the round ended)
    active: np.ndarray  # (N,) bool: still in the episode (alive and the round goes on)
    tick: int  # the simulator's tick of this state
    winner: str | None  # "T" or "CT" once the round has ended
    reason: str | None  # how it ended, named as in ESTA


@dataclass(slots=True)
class _Quiet:
    """What the steps from `tick` on share while they stay quiet (module docstring)."""

    tick: int  # the tick it holds at, moved on by each quiet step
    events: int  # how many events the round had then
    arrays: tuple[int, np.ndarray, int, int, np.ndarray, np.ndarray]  # `_quiet_step`'s horizon,
    # watched agents, bomb state, carrier, bomb position (the simulator's own array, which a
    # carried bomb's moves update) and round inputs

    @property
    def horizon(self) -> int:
        return self.arrays[0]

    @property
    def bomb_position(self) -> np.ndarray:
        return self.arrays[4]


class RoundSteps:
    """The environment's steps through one round of `sim`, whose policy takes its actions from
    `choices.given` (`array_env._ChosenActions`); `names` name the agents in error messages."""

    def __init__(
        self,
        sim: Simulator,
        encoder: ObservationEncoder,
        choices: Choices,
        names: list[str],
        is_t: np.ndarray,
    ) -> None:
        self.sim = sim
        self.encoder = encoder
        self.choices = choices
        self.names = names
        graph, agents, mover = sim.graph, sim.agents, sim.mover
        if not isinstance(mover, MoverBase):
            raise TypeError("the environment's steps need one of the package's movers")
        first, actions = graph.allowed_actions
        n = agents.count
        self._shapes = ((n, encoder.size), (n, NUM_ACTIONS), n)  # vectors, masks, the rest
        self._dtypes = (np.dtype(np.float32), np.dtype(np.bool_), np.dtype(np.int8))
        make = _round_arrays if jit_enabled() else _plain_round_arrays
        self._arrays = make(
            choices.given, choices.draws, first, actions, choices.hold_ticks, choices.plant,
            choices.defuse, choices.top_speeds.of(agents.weapon), graph.out_edges,
            graph.edge_target, graph.edge_kind, graph.fall_m, graph.positions, agents.node,
            agents.alive, agents.yaw, agents.hp, agents.armor, agents.helmet, agents.has_defuser,
            agents.position, sim.waiting, sim.hold_until, sim.decisions, sim.wants_plant,
            sim.wants_defuse, sim.goal_node, sim.fall_m, *mover.kernel_arrays(),
            mover.jump_speed, mover.gravity, is_t, *encoder.kernel_arrays(),
            np.zeros(n, np.bool_), np.ones(n, np.bool_),
        )  # fmt: skip
        self._quiet: _Quiet | None = None

    def state(self) -> ArrayStep:
        """The agents' state as it stands, no step taken (the round's start, for `reset`), as
        a step returns it."""
        return self._finish()

    def play(self, chosen: np.ndarray) -> ArrayStep:
        """Hand in the actions (N,) of the agents due, play the step (to the next tick an alive
        agent is due, or the round's end) and return the agents' state after it. ValueError for
        an action not 0..8.

        Quiet stretches are played by `_quiet_step`, a tick that is not quiet by
        `Simulator.step`; the first tick takes the actions handed in (`Simulator.step` asks the
        policy, `array_env._ChosenActions`, for them)."""
        sim = self.sim
        first = sim.tick
        hand_in = True
        while not sim.done and not (sim.tick > first and sim.decision_due):
            quiet = self._quiet_from_here()
            if quiet is None:
                if hand_in:
                    self._check(_hand_in(self._arrays, chosen), chosen)
                    hand_in = False
                sim.step()
                continue
            out = self._outputs()
            start = sim.tick
            status, agent, tick, made = _quiet_step(
                self._arrays, chosen, hand_in, start, *quiet.arrays, *out
            )
            if status == StepEnd.BAD_ACTION:
                self._check(agent, chosen)
            hand_in = False
            if tick > start:  # `_quiet_step` took the positions and the bomb over itself
                sim.note_quiet_play(tick, made, 0, False)
            if status == StepEnd.PLAYED:  # nothing ended
                quiet.tick = tick
                return ArrayStep(*out, tick, None, None)
            if status == StepEnd.IN_THE_AIR:
                raise ValueError("an agent due for a decision is in the air")
            if status == StepEnd.NOT_TAKEN:
                raise _not_taken(agent)
            if status == StepEnd.HALF_PLAYED:
                raise RuntimeError("a compiled step handed back in the middle of a tick")
            if tick == start:  # handed back before its first tick: play that one whole
                sim.step()
        return self._finish()

    def _quiet_from_here(self) -> _Quiet | None:
        """The shared state of quiet steps from the simulator's tick on, or None when the next
        tick is not quiet (`Simulator.quiet_horizon`, which also says so for a mover that is not
        kinematic): kept from the last quiet step when nothing else happened since, else asked
        anew."""
        sim = self.sim
        quiet = self._quiet
        if quiet is None or quiet.tick != sim.tick or quiet.events != len(sim.events):
            self._quiet = quiet = None
            horizon = sim.quiet_horizon()
            if horizon <= sim.tick:
                return None
            watched = sim.rules.watched(sim.agents, sim.bomb)
            state, carrier, inputs = self.encoder.round_inputs(sim)
            arrays = (horizon, watched, state, carrier, sim.bomb.position, inputs)
            self._quiet = quiet = _Quiet(sim.tick, len(sim.events), arrays)
        if quiet.horizon <= sim.tick or quiet.bomb_position is not sim.bomb.position:
            return None
        return quiet

    def _finish(self) -> ArrayStep:
        """The state after a step that ended in Python, or with no step (`state`)."""
        sim = self.sim
        self._quiet = None
        outcome = sim.outcome
        winner = -1 if outcome is None else int(outcome.winner == "T")
        state, carrier, inputs = self.encoder.round_inputs(sim)
        out = self._outputs()
        unused = _finish(
            self._arrays, winner, state, carrier, sim.bomb.position, inputs, sim.done, sim.tick,
            *out,
        )  # fmt: skip
        if unused >= 0:
            raise _not_taken(unused)
        if outcome is None:
            return ArrayStep(*out, sim.tick, None, None)
        return ArrayStep(*out, sim.tick, outcome.winner, outcome.reason)

    def _outputs(self) -> _Outputs:
        """New arrays for a step's state, in `ArrayStep`'s order (the caller keeps them)."""
        (vectors, masks, n), (reals, flags, small) = self._shapes, self._dtypes
        empty = np.empty
        return (
            empty(vectors, reals),
            empty(masks, small),
            empty(n, flags),
            empty(n, reals),
            empty(n, flags),
            empty(n, flags),
        )

    def _check(self, bad: int, chosen: np.ndarray) -> None:
        if bad >= 0:
            raise ValueError(f"{self.names[bad]}: action {chosen[bad]} is not in 0..8")


_Outputs = tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]
"""A step's new arrays, in `ArrayStep`'s order."""


def _not_taken(agent: int) -> RuntimeError:
    return RuntimeError(
        f"the simulator did not ask agent {agent} for the decision the environment collected"
    )


@njit_cached
def _hand_in(r, chosen):
    """Put the actions of the due agents (`r.due`) into `r.given` (-1 for the others); the
    first due agent whose action is not 0..8, or -1."""
    for i in range(r.due.shape[0]):
        r.given[i] = -1
        if r.due[i]:
            if not 0 <= chosen[i] < NUM_ACTIONS:
                return i
            r.given[i] = chosen[i]
    return -1


@njit_cached
def _finish(
    r, winner, bomb_state, carrier, bomb_pos, round_inputs, done, tick, obs, masks, due,
    rewards, terminated, active,
):  # fmt: skip
    """After a step, into the arrays given and the struct's own `due` and `active`: rewards
    (+1/-1 by side to the agents active before it, once the round is won: `winner` 1 T, 0 CT,
    -1 not yet), terminated, still active, and the observations, masks and due agents
    (`encode_into`). Returns an agent whose handed-in action the simulator did not take, or
    -1."""
    unused = -1
    for i in range(r.given.shape[0]):
        if r.given[i] >= 0:
            unused = i
        was_active = r.active[i]
        rewards[i] = 0.0
        active[i] = False
        if winner >= 0:
            if was_active:
                rewards[i] = 1.0 if r.is_t[i] == (winner == 1) else -1.0
        else:
            active[i] = was_active and r.alive[i]
        terminated[i] = was_active and not active[i]
    encode_into(
        obs, masks, due, r.starts, r.bomb_starts, r.pos, r.yaw, r.hp, r.armor, r.helmet, r.kit,
        r.is_ct, r.alive, r.mates, r.enemies, r.centre, r.half, bomb_pos, bomb_state, carrier,
        round_inputs, done, tick, r.waiting, r.hold_until, r.node, r.out_edges,
    )  # fmt: skip
    r.due[:] = due
    r.active[:] = active
    return unused


@njit_cached
def _hands_back(r, chosen, watch):
    """Whether an action handed in would end `_play`'s stretch with its first tick half played
    (`quiet_play.hands_back`). A move no edge makes `_play` leaves to Python before the tick."""
    for i in range(r.due.shape[0]):
        if r.due[i] and hands_back(
            i, chosen[i], r.node[i], watch, r.plant, r.defuse, r.out_edges, r.edge_fall
        ):
            return True
    return False


@njit_cached
def _quiet_step(
    r, chosen, hand_in, tick, horizon, watch, bomb_state, carrier, bomb_pos, round_inputs, obs,
    masks, due, rewards, terminated, active,
):  # fmt: skip
    """A step's quiet stretch from `tick` through at most `horizon`: the actions handed in
    first (if `hand_in`: they are taken at the stretch's first tick, unless one may hand back,
    `_hands_back`), then decisions and motion (`_play`) up to the next tick an agent is due,
    where the step ends and its state is written as `_finish` writes it. After a glide the
    agents' positions and a carried bomb's are taken over from the mover. Returns how it
    ended, the bad or untaken agent (else -1), the tick reached and the decisions made."""
    if hand_in:
        bad = _hand_in(r, chosen)
        if bad >= 0:
            return StepEnd.BAD_ACTION, bad, tick, 0
        if _hands_back(r, chosen, watch):
            return StepEnd.LEFT_TO_RUN, -1, tick, 0
    reached, _, made, _, glide_end, status = _play(
        tick, horizon, r.given, r.draws, 0, r.first, r.actions, r.hold_ticks, r.plant,
        r.defuse, NEVER, watch, r.top, r.out_edges, r.edge_target, r.edge_kind, r.edge_fall,
        r.positions, r.node, r.alive, r.yaw, r.waiting, r.hold_until, r.decisions,
        r.wants_plant, r.wants_defuse, r.goal_node, r.fall_m, r.mpos, r.start, r.target, r.fv,
        r.iv, r.flags, r.prm, r.jump_speed, r.gravity,
    )  # fmt: skip
    if glide_end >= 0:  # as `Simulator.note_quiet_play` and `BombRules.follow` take them
        r.pos[:] = r.mpos
        if carrier >= 0:
            bomb_pos[:] = r.pos[carrier]
    if status == StretchEnd.AIRBORNE:
        return StepEnd.IN_THE_AIR, -1, reached, made
    if status == StretchEnd.DECIDED:  # `_hands_back` missed a way back: the tick is half played
        return StepEnd.HALF_PLAYED, -1, reached, made
    # (an agent due with no action: Python says whom)
    if status != StretchEnd.DUE or reached == tick:
        return StepEnd.LEFT_TO_RUN, -1, reached, made
    unused = _finish(
        r, -1, bomb_state, carrier, bomb_pos, round_inputs, False, reached, obs, masks, due,
        rewards, terminated, active,
    )  # fmt: skip
    if unused >= 0:
        return StepEnd.NOT_TAKEN, unused, reached, made
    return StepEnd.PLAYED, -1, reached, made
