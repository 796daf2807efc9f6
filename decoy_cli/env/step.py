"""The environment's steps of one round: quiet stretches in compiled code, other ticks by
`Simulator.step`, with the result of stepping every tick.

A step plays from the actions handed in to the next tick an alive agent is due (or the round's
end). Most steps of a round with ten agents are quiet: the agents due take their actions,
everybody glides to the next arrival or end of a STOP, and nothing else happens (no combat
step, no recorded tick, no bomb rule, no fall). `_quiet_step` plays such a stretch, and the
step's rewards and observations, in one compiled call; `RoundSteps.play` plays a tick that is
not quiet (a combat step, a plant, a fall) with `Simulator.step` and goes on.

The arrays go to compiled code as one struct that holds them, not copies (`EnvStruct`: the
round's, `Simulator.state`, the choices' and the environment's own), since
numba's dispatch checks and converts every argument of every call, and a step is short.

Why a quiet step may skip what `Simulator.run` asks before every stretch: the stretch's
horizon (`Simulator.quiet_horizon`), the agents the bomb rules watch and the round's observation
inputs (`ObservationEncoder.round_inputs`) change only on ticks that are not quiet, so they are
asked after each such tick (or anything else that added an event) and kept while the steps stay
quiet.
"""

from __future__ import annotations

from dataclasses import dataclass
from enum import IntEnum

import numpy as np
from numba.experimental import structref

from decoy_cli.compiled import njit_cached
from decoy_cli.env.observation import NUM_ACTIONS, ObservationEncoder, encode_into
from decoy_cli.sim.engine import Simulator
from decoy_cli.sim.quiet_play import Choices, StretchEnd, hands_back, play_quiet
from decoy_cli.sim.round_state import StructBase, pack
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


# ---- the environment's arrays as one struct ---------------------------------------------------


@structref.register
class _EnvType(StructBase):
    pass


class EnvStruct(structref.StructRefProxy):
    """What compiled steps take of one round of the environment, as one struct: the round's
    (`round`: `RoundState.kernel`), the choices' (`Choices.arrays`), the encoder's
    (`ObservationEncoder.kernel_arrays`), who is a T, and its own `due` (whose actions the next
    step takes) and `active` (in the episode)."""


ENV_FIELDS = ("round", "given", "draws", "plant", "defuse", "top", "hold_ticks", "is_t",
              "starts", "bomb_starts", "is_ct", "mates", "enemies", "centre", "half", "due",
              "active")  # fmt: skip
"""`EnvStruct`'s fields, in order."""

structref.define_proxy(EnvStruct, _EnvType, list(ENV_FIELDS))


@njit_cached
def _env_struct(*values):
    """An `EnvStruct` made in compiled code, so that its constructor is cached with it."""
    return EnvStruct(*values)


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
    horizon: int  # the stretch's last quiet tick (`Simulator.quiet_horizon`)
    watched: np.ndarray  # the agents the bomb rules watch
    bomb: _BombInputs

    @property
    def bomb_position(self) -> np.ndarray:
        return self.bomb[2]


_BombInputs = tuple[int, int, np.ndarray, np.ndarray]
"""What `encode_into` takes of the bomb and the round: the bomb state, its carrier, its position
(the simulator's own array, which a carried bomb's moves update) and the round inputs."""


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
        n = sim.agents.count
        self._shapes = ((n, encoder.size), (n, NUM_ACTIONS), n)  # vectors, masks, the rest
        self._dtypes = (np.dtype(np.float32), np.dtype(np.bool_), np.dtype(np.int8))
        top = choices.top_speeds.of(sim.agents.weapon)
        env = (
            sim.state.kernel, choices.given, choices.draws, choices.plant, choices.defuse, top,
            choices.hold_ticks, is_t, *encoder.kernel_arrays(), np.zeros(n, np.bool_),
            np.ones(n, np.bool_),
        )  # fmt: skip
        self._env = pack(_env_struct, ENV_FIELDS, env)
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
                    self._check(_hand_in(self._env, chosen), chosen)
                    hand_in = False
                sim.step()
                continue
            out = self._outputs()
            start = sim.tick
            inputs = (chosen, hand_in, start, quiet.horizon, quiet.watched, quiet.bomb, out)
            status, agent, tick, made = _quiet_step(self._env, *inputs)
            if status == StepEnd.BAD_ACTION:
                self._check(agent, chosen)
            hand_in = False
            if tick > start:  # `_quiet_step` took the positions and the bomb over itself
                sim.note_quiet_play(tick, made, 0)
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
            bomb = (state, carrier, sim.bomb.position, inputs)
            self._quiet = quiet = _Quiet(sim.tick, len(sim.events), horizon, watched, bomb)
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
        bomb = (state, carrier, sim.bomb.position, inputs)
        out = self._outputs()
        unused = _finish(self._env, winner, bomb, sim.done, sim.tick, out)
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
def _hand_in(e, chosen):
    """Put the actions of the due agents (`e.due`) into `e.given` (-1 for the others); the
    first due agent whose action is not 0..8, or -1."""
    given, due = e.given, e.due
    for i in range(due.shape[0]):
        given[i] = -1
        if due[i]:
            if not 0 <= chosen[i] < NUM_ACTIONS:
                return i
            given[i] = chosen[i]
    return -1


@njit_cached
def _finish(e, winner, bomb, done, tick, out):
    """After a step, into `out` (`ArrayStep`'s arrays) and `e`'s own `due` and `active`:
    rewards (+1/-1 by side to the agents active before it, once the round is won: `winner` 1 T,
    0 CT, -1 not yet), terminated, still active, and the observations, masks and due agents
    (`encode_into`). Returns an agent whose handed-in action the simulator did not take, or
    -1."""
    _, _, due, rewards, terminated, active = out
    r = e.round
    given, was, is_t, alive = e.given, e.active, e.is_t, r.alive
    unused = -1
    for i in range(given.shape[0]):
        if given[i] >= 0:
            unused = i
        was_active = was[i]
        rewards[i] = 0.0
        active[i] = False
        if winner >= 0:
            if was_active:
                rewards[i] = 1.0 if is_t[i] == (winner == 1) else -1.0
        else:
            active[i] = was_active and alive[i]
        terminated[i] = was_active and not active[i]
    encode_into(r, e, bomb, done, tick, out)
    e.due[:] = due
    e.active[:] = active
    return unused


@njit_cached
def _hands_back(e, chosen, watch):
    """Whether an action handed in would end `play_quiet`'s stretch with its first tick half
    played (`quiet_play.hands_back`). A move no edge makes `play_quiet` leaves to Python before
    the tick."""
    r, due = e.round, e.due
    for i in range(due.shape[0]):
        if due[i] and hands_back(
            i, chosen[i], r.node[i], watch, e.plant, e.defuse, r.out_edges, r.edge_fall
        ):
            return True
    return False


@njit_cached
def _quiet_step(e, chosen, hand_in, tick, horizon, watch, bomb, out):
    """A step's quiet stretch from `tick` through at most `horizon`: the actions handed in
    first (if `hand_in`: they are taken at the stretch's first tick, unless one may hand back,
    `_hands_back`), then decisions and motion (`play_quiet`, which moves a carried bomb,
    `bomb`: `_BombInputs`) up to the next tick an agent is due, where the step ends and its
    state is written as `_finish` writes it. Returns how it ended (a
    `StepEnd` value as a plain int: an enum costs a Python call per step to return), the bad or
    untaken agent (else -1), the tick reached and the decisions made."""
    if hand_in:
        bad = _hand_in(e, chosen)
        if bad >= 0:
            return StepEnd.BAD_ACTION.value, bad, tick, 0
        if _hands_back(e, chosen, watch):
            return StepEnd.LEFT_TO_RUN.value, -1, tick, 0
    r = e.round
    c = (e.given, e.draws, e.plant, e.defuse, e.top, e.hold_ticks)
    # constants typed as a call from Python types them (np.int64, np.bool_; a bare 0 or False
    # is a literal type): `play_quiet` and `_finish` compile once for both callers
    first_draw, no_limit = np.int64(0), np.int64(NEVER)
    reached, _, made, _, status = play_quiet(
        r, c, tick, horizon, first_draw, no_limit, watch, bomb[1], bomb[2]
    )
    if status == StretchEnd.AIRBORNE:
        return StepEnd.IN_THE_AIR.value, -1, reached, made
    if status == StretchEnd.DECIDED:  # `_hands_back` missed a way back: the tick is half played
        return StepEnd.HALF_PLAYED.value, -1, reached, made
    # (an agent due with no action: Python says whom)
    if status != StretchEnd.DUE or reached == tick:
        return StepEnd.LEFT_TO_RUN.value, -1, reached, made
    unused = _finish(e, np.int64(-1), bomb, np.bool_(False), reached, out)
    if unused >= 0:
        return StepEnd.NOT_TAKEN.value, unused, reached, made
    return StepEnd.PLAYED.value, -1, reached, made
