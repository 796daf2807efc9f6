"""The simulator: one round of agents on the waypoint graph, tick by tick at 60 Hz.

Each tick:

1. agents that reached their waypoint (or finished a STOP) ask their policy for the next action
   (asynchronous, on demand: the paper's 8 compass moves along graph edges, or STOP for a given
   time, never collapsed);
2. the mover advances every agent one tick along its edge;
3. the bomb rules advance (plant, detonation, defuse, pickup);
4. every `combat_every_ticks` ticks (by integer tick count) the combat step runs: line of sight
   between all alive enemy pairs in one batch, the damage model on the visible pairs, damage
   applied simultaneously; deaths drop the bomb and stop the agent;
5. the round outcome is checked; state is recorded at the requested ticks.

Every loop is bounded by the round's time limit (plus the bomb timer after a plant), so a run
always ends. The policy, the mover, the damage model and the recording are pluggable; the engine
itself knows nothing of ESTA data (the replay is one policy among others).

This module is the tick driver; beside it are the quiet ticks it crosses in one go
(`quiet_ticks`), the damaging drops and their landings (`falls`), when the outcome is judged
(`judging`) and the changes made to a round from outside its rules (`outside_changes`).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import Protocol

import numpy as np

from decoy_cli.csgo import TICK_RATE
from decoy_cli.sim.decisions import REFUSED, Decision, Taken, take_decision
from decoy_cli.sim.falls import Falls
from decoy_cli.sim.judging import OutcomeJudge
from decoy_cli.sim.movement import KinematicMover, MoveStep
from decoy_cli.sim.movement.base import MoverBase
from decoy_cli.sim.movement.interface import ARRIVAL, STUCK, TELEPORT
from decoy_cli.sim.outside_changes import OutsideChanges
from decoy_cli.sim.quiet_play import QuietPlayer, StretchEnd, decide_tick
from decoy_cli.sim.quiet_ticks import play_stretches, quiet_until, stretch_end
from decoy_cli.sim.recording import Recorder, Recording
from decoy_cli.sim.round_state import RoundState, take_motion
from decoy_cli.sim.rules import BombRules
from decoy_cli.sim.schedule import NEVER
from decoy_cli.sim.state import Agents, Bomb, RoundOutcome, SimEvent
from decoy_cli.waypoints.graph import WaypointGraph
from decoy_cli.weapons import max_speed_m_s


class Policy(Protocol):
    """Chooses the next action of an agent that is waiting for one."""

    def decide(self, sim: Simulator, agent: int) -> Decision: ...


COMBAT_EVERY_TICKS = TICK_RATE // 2
"""Ticks between combat steps: the paper's 0.5 s."""


class CombatRunner(Protocol):
    """A combat step: changes the agents in place and returns the events (see sim/combat.py)."""

    def run(self, agents: Agents, tick: int, rng: np.random.Generator) -> list[SimEvent]: ...


class Simulator(OutsideChanges):
    """One round; build it, then `run()` (or `step()` yourself, as the environment does).

    Rounds are normally opened with `decoy_cli.sim.setup.open_round`, which builds the mover,
    the rules and the combat step from one `RoundSetup`; constructing it directly is for tests
    and for callers that bring their own parts. `combat` None: nobody shoots.
    """

    def __init__(
        self,
        graph: WaypointGraph,
        agents: Agents,
        mover: MoverBase,
        policy: Policy,
        rules: BombRules,
        *,
        bomb_carrier: int = -1,
        combat: CombatRunner | None = None,
        combat_every_ticks: int = COMBAT_EVERY_TICKS,
        kills: bool = True,
        start_tick: int = 0,
        record_ticks: Sequence[int] = (),
        seed: int | None = None,
    ) -> None:
        if combat_every_ticks < 1:
            raise ValueError(f"combat_every_ticks must be >= 1, got {combat_every_ticks}")
        self.graph = graph
        self.agents = agents
        self.mover = mover
        self.policy = policy
        self.rules = rules
        self.combat = combat
        self.combat_every_ticks = int(combat_every_ticks)
        self.rng = np.random.default_rng(seed)
        self.tick = start_tick
        self.events: list[SimEvent] = []
        self.outcome: RoundOutcome | None = None
        self.mover.reset(
            agents.position, max_speed=np.array([max_speed_m_s(str(w)) for w in agents.weapon])
        )
        self.state = RoundState.open(agents, mover, graph)
        """The round's decision arrays (who waits, STOPs, wants to plant or defuse, is on a
        drop) beside the agents, the mover and the graph; compiled code takes all their arrays
        as one struct."""
        self.falls = Falls(self.state, kills)  # kills False: a fall stops at 1 HP
        self.decision_count = 0  # state.decisions.sum(), kept as they are made
        self._deciding = -1  # the agent whose policy is deciding right now
        self._player = policy if isinstance(policy, QuietPlayer) else None  # decides compiled
        for agent in np.flatnonzero(~agents.alive):  # dead from the start: no body to bump into
            self.mover.remove(int(agent))
        self.bomb: Bomb = rules.start(agents, bomb_carrier)
        self.recorder = Recorder(record_ticks, agents.count, self.events)
        self.recording = self.recorder.recording
        self.judge = OutcomeJudge(rules)
        # every loop is bounded: the round's time limit plus the bomb timer after a plant
        self._max_tick = start_tick + rules.config.round_ticks + rules.config.bomb_ticks + 1
        self._record()

    # ---- the tick -----------------------------------------------------------------------------

    @property
    def done(self) -> bool:
        return self.outcome is not None or self.tick >= self._max_tick

    def step(self, *, after_end: bool = False) -> list[SimEvent]:
        """Advance one tick; returns the events of that tick. Nothing happens once the round is
        done, unless `after_end`: then, after the outcome, the agents go on moving and are
        recorded (a replay following the data through the round-end delay, when real players
        still move), while the rules, combat and the outcome stay as they ended."""
        if self.done and not (after_end and self.outcome is not None):
            return []
        start = len(self.events)
        self._advance(self.tick + 1)
        return self.events[start:]

    def _advance(
        self,
        end: int,
        stop: Callable[[], bool] | None = None,
        player: QuietPlayer | None = None,
        limit: int = NEVER,
    ) -> None:
        """Decide, then move: the one driver of the round's ticks (`step`, `run`), from this
        tick through at most `end`. With a `player` (`run`'s `QuietPlayer`) and the next ticks
        quiet, a stretch of them is handed to compiled code (`quiet_ticks.play_stretches`, up
        to `limit` decisions in all); otherwise, or when that stretch ends with a tick half
        played, the next tick's decisions are made here and then its motion:

        * after the outcome, with that of the ticks after it on which no decision falls due and
          nothing is recorded, in one mover call (the rules, combat and the outcome stay);
        * glided with the quiet ticks after it (`_glide`) when `stop` says go on;
        * else (no `stop`: `step`) played whole with the rest of the tick (`_finish_tick`)."""
        decided = False
        if player is not None and self.outcome is None and not self.falls.count:
            horizon = stretch_end(self, self.tick, end)
            if horizon > self.tick:
                before = (self.tick, self.decision_count)
                watched = self.rules.watched(self.agents, self.bomb)
                decided = (
                    play_stretches(self, player, horizon, limit, watched) == StretchEnd.DECIDED
                )
                if not decided and (self.tick, self.decision_count) != before:
                    return  # the caller asks its stopping rules again
        if not decided:
            self.tick += 1
            self._decide()
        if self.outcome is not None:
            last = min(end, self.state.next_due(self.tick) - 1, self.recorder.next_tick - 1)
            ticks, moved = self.mover.glide(max(1, last - self.tick + 1))
            self.tick += ticks - 1
            self._moved(moved)
            self._record()
            return
        if stop is not None and not stop():
            last = min(quiet_until(self, self.tick - 1), end)
            if last >= self.tick:
                self._glide(last)
                return
        self._finish_tick(self._move())

    def _finish_tick(self, moving: np.ndarray) -> None:
        """The rest of a tick after the decisions and the motion: the bomb rules, the combat
        step, the outcome and the recording."""
        agents = self.agents
        self._step_rules(moving)
        if self.combat is not None and self.tick % self.combat_every_ticks == 0:
            alive_before = agents.alive.copy()
            self.events += self.combat.run(agents, self.tick, self.rng)
            for agent in np.nonzero(alive_before & ~agents.alive)[0]:
                self._kill(int(agent))
        self._judge_and_announce()
        self._record()

    def _judge_and_announce(self) -> None:
        """Judge the outcome (`OutcomeJudge`); a "round_end" event the moment there is one."""
        self.falls.killed = False
        if self.outcome is not None:
            return
        self.outcome = self.judge.judge(self.tick, self.agents, self.bomb)
        if self.outcome is not None:
            self.events.append(
                SimEvent(
                    self.tick,
                    "round_end",
                    data={"winner": self.outcome.winner, "reason": self.outcome.reason},
                )
            )

    def run(
        self,
        until: Callable[[Simulator], bool] | None = None,
        *,
        to_tick: int | None = None,
        after_end: bool = False,
        max_decisions: int | None = None,
    ) -> Recording:
        """Play until the round ends (the tick bound), `to_tick` is reached, `until(sim)` says
        stop or this run has made `max_decisions` decisions; with `after_end`, the agents go on
        moving after the outcome, as `step(after_end=True)` has them, until `to_tick`. The
        stopping rules are asked as `until` is.

        Event by event: after each tick's decisions, the ticks from there on at which nothing
        but motion can happen are crossed by the mover in one call (`glide`), which stops at
        the first arrival; every other tick is played whole, as `step` plays it. The result is
        tick for tick what stepping every tick gives. `until` is asked after each played tick
        or glide, and after each tick's decisions (when it then says stop, the tick is played
        whole without a glide and `until` is asked again): wherever anything but motion may have
        happened, so a predicate on decisions, events, deaths or the bomb stops the run at the
        tick stepping would. Motion alone (positions, the tick) changes inside a glide unseen:
        to stop at a tick give `to_tick`; to watch positions, `step`.

        A `quiet_play.QuietPlayer` policy (the random policy) has whole quiet stretches of
        decisions and motion played in compiled code when the mover is kinematic and no `until`
        is given, with the same result. Each pass of the loop is one `_advance`."""
        end = self._max_tick if to_tick is None else int(to_tick)
        limit = NEVER if max_decisions is None else self.decision_count + int(max_decisions)

        def stop() -> bool:
            return self.decision_count >= limit or (until is not None and until(self))

        player = None
        if until is None and isinstance(self.mover, KinematicMover):
            player = self._player
        while self.tick < end and not stop():
            if self.done and not (after_end and self.outcome is not None):
                break
            self._advance(end, stop, player, limit)
        return self.recording

    def note_quiet_play(self, tick: int, made: int, falls: int) -> None:
        """Take over a quiet stretch played in compiled code (`quiet_play.play_quiet`, from
        `run` or the environment's steps): the tick it reached, the decisions it made and the
        damaging drops they started (the agents, the mover and a carried bomb it moved itself)."""
        self.tick = tick
        self.decision_count += made
        self.falls.count += falls

    def quiet_horizon(self) -> int:
        """The last tick through which nothing but decisions and motion can happen from here
        (`quiet_ticks.stretch_end`), for a caller that plays quiet stretches itself, as `run`
        hands them to a `quiet_play.QuietPlayer` (the environment's steps, `env_step`); the tick
        itself when the next is not quiet, the round is done, an agent is on a damaging drop or
        the mover is not kinematic."""
        if self.done or self.falls.count or not isinstance(self.mover, KinematicMover):
            return self.tick
        return stretch_end(self, self.tick, self._max_tick)

    # ---- internals ----------------------------------------------------------------------------

    def _move(self) -> np.ndarray:
        """Move every agent one tick; returns the (N,) mask of the agents that moved."""
        return self._moved(self.mover.step())

    def _moved(self, moved: MoveStep) -> np.ndarray:
        """Take over what the mover did (positions, yaw) and note the last tick's arrivals,
        stuck agents and teleports; returns the (N,) mask of the agents that moved then."""
        take_motion(self.state.kernel)
        if moved.happened & ARRIVAL and self.falls.count:
            self.falls.land(
                moved.arrived,
                self.tick,
                self.agents,
                self.events,
                self.outcome is not None,
                self.kill,
            )
        if moved.happened & STUCK:
            for agent in np.flatnonzero(moved.stuck).tolist():
                self.events.append(SimEvent(self.tick, "stuck", agent))
        if moved.happened & TELEPORT:
            for agent in np.flatnonzero(moved.teleported).tolist():
                self.events.append(SimEvent(self.tick, "teleport", agent))
        return moved.moving

    def _glide(self, last: int) -> None:
        """Play the motion of this tick (its decisions are made) and of the quiet ticks after it
        up to `last` (`quiet_ticks.quiet_until`) in one mover call; it stops after the first tick
        with an arrival, a stuck agent or a teleport, which is then noted as `step` notes it. The
        bomb rules have nothing to do on quiet ticks but follow the carrier, so stepping them
        once, at the last tick, is the same as stepping them at every tick."""
        ticks, moved = self.mover.glide(last - self.tick + 1)
        self.tick += ticks - 1
        self._step_rules(self._moved(moved))
        if self.falls.killed:  # at the glide's last tick
            self._judge_and_announce()

    def _step_rules(self, moving: np.ndarray) -> None:
        """The bomb rules' tick (`BombRules.step`), with the agents that `moving` says moved."""
        state = self.state
        self.events += self.rules.step(
            self.tick, self.agents, self.bomb, state.wants_plant, state.wants_defuse, moving
        )

    @property
    def decision_due(self) -> bool:
        """Whether some agent will ask its policy for an action at the next tick."""
        return not self.done and self.state.next_due(self.tick) == self.tick + 1

    @property
    def needs_decision(self) -> np.ndarray:
        """(N,) bool: agents that will ask their policy for an action at the next tick."""
        due = np.zeros(self.agents.count, dtype=bool)
        if not self.done:
            due[self.state.due(self.tick + 1)] = True
        return due

    def _decide(self) -> None:
        """The due agents (ascending) ask the policy and the round takes each decision
        (`take_decision`) before the next agent is asked; a `QuietPlayer`'s in compiled code."""
        agents, state = self.agents, self.state
        due = state.due(self.tick)
        if self._player is not None and len(due):
            made, falls = decide_tick(state, self.tick, self._player, agents.weapon)
            self.decision_count += made
            self.falls.count += falls
            return
        for agent in due.tolist():
            state.hold_until[agent] = 0
            state.waiting[agent] = False
            self._deciding = agent
            decision = self.policy.decide(self, agent)
            self._deciding = -1
            self.decision_count += 1
            top = decision.max_speed
            top = max_speed_m_s(str(agents.weapon[agent])) if top is None else float(top)
            speed = top if decision.speed is None else min(float(decision.speed), top)
            taken, falls = take_decision(
                self.state.kernel, agent, decision.action, speed, top,
                max(1, int(decision.hold_ticks)), decision.plant, decision.defuse, self.tick,
            )  # fmt: skip
            self.falls.count += falls
            if taken == Taken.NO_EDGE:  # held as a STOP, and recorded
                data = {"action": decision.action}
                self.events.append(SimEvent(self.tick, "invalid_action", agent, data=data))
            elif taken > Taken.NO_EDGE:
                raise ValueError(f"agent {agent} {REFUSED[Taken(taken)]}: {decision}")

    def _record(self) -> None:
        self.recorder.take(self.tick, self.agents, self.done)
