"""Replay a real round in the simulator, kept in time with the data.

The timed plans of `snap_round` drive the agents through `PlanPolicy` (replay/policy.py): each
move runs at the speed that reaches the interval's target waypoint by its frame time, a STOP
holds until the deadline, and the arrival at every target is logged against its deadline (the
lateness). The anchor implementation moved everyone at knife speed, collapsed STOPs and killed
every agent at the end of its actions; here a survivor survives, and a player who died in the
data is removed at its death time when combat is off or the deaths follow the data
(`ReplayOptions.deaths`, "scripted" deaths, recorded as such). Otherwise the simulation's own
fight kills, and a player the data shows dead whom the fight has not killed within
`DEATH_WINDOW_S` of its real death (the tolerance of the kill-level metrics) is removed then,
as "scripted" too: its data has ended, there is nothing left to replay, and a player standing
on at the spot where he died would fight a round that no longer exists. From his real death to
that removal he is a target only: he holds no weapon (in the game he is dead and shoots nobody;
armed, he killed players who survived in reality). The metrics count such deaths as not
reproduced by the fight.

Fields the game needs and the data lacks (weapons, armour, the bomb's carrier, the defuser) are
filled by the rules of `decoy_cli.replay.missing` and named in `ReplayResult.inferred`.

The state of every agent is recorded at every data frame time, so the metrics compare O_t and
S_t on the same clock.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from functools import cached_property

import numpy as np
import pandas as pd

from decoy_cli.csgo import TICK_RATE, tick_at
from decoy_cli.errors import EstaError
from decoy_cli.esta import Round
from decoy_cli.esta.plausibility import Implausible, first_offender
from decoy_cli.metrics.kills import DEATH_WINDOW_S, kill_row
from decoy_cli.metrics.players import ReplayTrace
from decoy_cli.replay.bomb import (
    DataBomb,
    carrier_sites,
    defuse_windows,
    follow_data_bomb,
    policy_plant,
    read_data_bomb,
)
from decoy_cli.replay.bomb_fidelity import BombRow, bomb_fidelity
from decoy_cli.replay.deaths import DeathProtocol, RoundDeaths, data_deaths, replay_deaths
from decoy_cli.replay.lateness import lateness_table
from decoy_cli.replay.missing import Missing, contradictions, fill_missing
from decoy_cli.replay.policy import AgentLog, PlanPolicy
from decoy_cli.replay.rounds import RoundPlan, snap_round
from decoy_cli.replay.utility import round_utility
from decoy_cli.sim.combat import DamageModel
from decoy_cli.sim.recording import Recording
from decoy_cli.sim.rules import RulesConfig
from decoy_cli.sim.setup import OpenRound, RoundSetup, RunSpec, open_round
from decoy_cli.sim.state import Agents, RoundOutcome, SimEvent
from decoy_cli.waypoints.graph import WaypointGraph
from decoy_cli.weapons import FIREARMS
from decoy_cli.world.occlusion import OcclusionScene
from decoy_cli.world.physics import PhysicsWorld


@dataclass
class ReplayResult:
    """A replayed round: the recording at the data's frame clock and what the replay did."""

    plan: RoundPlan
    recording: Recording
    frame_ticks: np.ndarray  # (F,) simulator tick of each data frame
    scripted_death: np.ndarray  # (P,) bool: removed at its data death time, not by combat
    logs: list[AgentLog]
    outcome: RoundOutcome | None
    data_deaths: RoundDeaths  # the data's death times and killers (replay/deaths.py)
    events: list[SimEvent] = field(default_factory=list)
    stuck: np.ndarray | None = None  # (P,) stuck episodes
    recoveries: np.ndarray | None = None  # (P,) recoveries (teleports) by the mover
    played_out_s: float = 0.0  # game seconds simulated after the data's last frame (play_out)
    warnings: tuple[str, ...] = ()  # implausible data replayed anyway (ReplayOptions.implausible)
    inferred: tuple[str, ...] = ()  # fields the data lacked, filled by rule (replay/missing.py)
    contradictions: tuple[str, ...] = ()  # what the data's frames and events say against each other
    bomb: DataBomb | None = None  # the data's bomb, when the replay followed it
    utility: dict[str, int] | None = None
    """The data's smokes, fires and blinds the fight heeded (replay/utility.py); None: the
    round has none, or nobody shot."""

    def bomb_row(self) -> BombRow | None:
        """The bomb fidelity of this replay (`BOMB_COLUMNS`), None when the bomb was off."""
        return None if self.bomb is None else bomb_fidelity(self.bomb, self.events)

    @cached_property
    def deaths(self) -> RoundDeaths:
        """The replay's deaths, from its events (replay/deaths.py)."""
        return replay_deaths(self.events, len(self.plan.plans))

    def kill_row(self, round_: Round) -> dict[str, object]:
        """The kill-level fidelity of this replay of `round_` (`KILL_COLUMNS`)."""
        truth = self.data_deaths
        replay = self.deaths
        alive = np.asarray(round_.alive, bool) & np.asarray(round_.present, bool)
        return kill_row(
            [p.name for p in self.plan.players],
            [p.side for p in self.plan.players],
            (truth.seconds, truth.killer),
            (replay.seconds, replay.killer, replay.by_fight),
            alive,
            self.recording.alive.T & np.asarray(round_.present, bool),
        )

    def trace(self) -> ReplayTrace:
        """What the fidelity metrics need from this replay (`decoy_cli.metrics.player_metrics`)."""
        lateness = self.lateness_table()
        count = len(self.logs)
        return ReplayTrace(
            position=self.recording.position,
            alive=self.recording.alive,
            died_original=np.array([plan.death_frame >= 0 for plan in self.plan.plans], bool),
            scripted_death=self.scripted_death,
            late_share=lateness["late_share"].to_numpy(dtype=float),
            targets=lateness["reached"].to_numpy(dtype=np.int64),
            late_over_frame=lateness["late_over_frame"].to_numpy(dtype=np.int64),
            late_zigzag=lateness["late_zigzag"].to_numpy(dtype=np.int64),
            late_detour=lateness["late_detour"].to_numpy(dtype=np.int64),
            late_speed=lateness["late_speed"].to_numpy(dtype=np.int64),
            late_gap=lateness["late_gap"].to_numpy(dtype=np.int64),
            late_replay=lateness["late_replay"].to_numpy(dtype=np.int64),
            late_p95_s=lateness["late_p95_s"].to_numpy(dtype=float),
            stuck=self.stuck if self.stuck is not None else np.zeros(count, np.int64),
            recoveries=self.recoveries
            if self.recoveries is not None
            else np.zeros(count, np.int64),
            relocations=lateness["relocations"].to_numpy(dtype=np.int64),
        )

    def lateness_table(self) -> pd.DataFrame:
        """Per player: targets, lateness and its causes (`replay.lateness.lateness_table`)."""
        return lateness_table(self.plan, self.logs)


@dataclass(frozen=True, kw_only=True)
class ReplaySpec(RunSpec):
    """A replay's switches, seed and protocols, as the command line gives them: what
    `ReplayOptions` and the evaluation's settings (`EvalSettings`) share.

    `combat` and `bomb` are independent switches; both off is the paper's movement-only
    replay. `deaths` says who decides deaths when shooting (module docstring); `missing`
    whether absent fields are filled or fail the round.
    """

    deaths: DeathProtocol = "simulated"
    missing: Missing = "infer"
    implausible: Implausible = "fail"
    """Whether a player far off the map fails the round or is a warning (as the reader's
    policy for the round's other implausible data, decoy_cli/esta/plausibility.py)."""
    rate: float | None = None
    """Frames a second read from awpy's full-rate ticks (None: the reader's default,
    decoy_cli/esta/awpy/rounds.py); ESTA files and data sampled at or below it are read as
    they are."""


@dataclass(frozen=True, kw_only=True)
class ReplayOptions(ReplaySpec):
    """How to replay: the spec (`ReplaySpec`), the damage model shooting needs, and where line
    of sight is tested."""

    damage_model: DamageModel | None = None
    # With shooting, a round still undecided when the data ends (the replay's fights went
    # otherwise than the real ones) is played on, every agent holding its last waypoint and
    # planting or defusing where the data did, until the rules end it (elimination, the bomb,
    # the clock). Real frames end at the round's end, so without this most replays of a
    # combat round end "undecided" and outcome agreement measures nothing. The result says
    # which outcomes were decided after the data (`ReplayResult.played_out_s`).
    play_out: bool = True
    sight: OcclusionScene | None = None
    """The map's geometry line of sight is tested in (`RoundSetup.sight`; None: the world)."""

    @classmethod
    def of(
        cls,
        spec: ReplaySpec,
        damage_model: DamageModel | None,
        *,
        seed: int | None = None,
        sight: OcclusionScene | None = None,
    ) -> ReplayOptions:
        """The options of a replay as `spec` says (a command's, an evaluation's settings),
        shooting with `damage_model` (None: no shooting), at `seed` when given."""
        return cls(
            mover=spec.mover,
            combat=spec.combat and damage_model is not None,
            bomb=spec.bomb,
            seed=spec.seed if seed is None else seed,
            deaths=spec.deaths,
            missing=spec.missing,
            implausible=spec.implausible,
            rate=spec.rate,
            damage_model=damage_model,
            sight=sight,
        )

    def setup(self, graph: WaypointGraph, round_: Round) -> RoundSetup:
        """The simulator setup of a replay of `round_` on `graph`."""
        rules = RulesConfig(auto_pickup=False)  # the data says who picks the bomb up
        if not self.bomb and len(round_.frame_seconds):
            # Without the bomb, a round whose data ran past the round time (after a plant,
            # which stops the clock) would time out while the players still move: replay it
            # to the end of its data.
            last = float(round_.frame_seconds[-1])
            rules = replace(rules, round_time_s=max(rules.round_time_s, last + 1.0))
        return RoundSetup(
            graph=graph,
            mover=self.mover,
            combat=self.combat,
            bomb=self.bomb,
            damage_model=self.damage_model,
            kills=self.deaths == "simulated",
            rules=rules,
            sight=self.sight,
            utility=round_utility(round_),
        )


def replay_round(
    round_: Round,
    graph: WaypointGraph,
    options: ReplayOptions | None = None,
    *,
    physics: PhysicsWorld | None = None,
    open_sim: OpenRound = open_round,
) -> ReplayResult:
    """Snap, plan and replay one round; see the module docstring.

    `physics` lends a pybullet client of the map's world (a batch keeps one per worker); without
    it the replay opens its own for the round. `open_sim` builds the simulator (default
    `open_round`; a test may inject its own). A round without frames (an events-only round)
    raises EstaError: there is nothing to replay.
    """
    options = options if options is not None else ReplayOptions()
    frame_ticks = _frame_ticks(round_)
    setup = options.setup(graph, round_)
    if physics is None:  # snapping finds frames in the air with the world's rays
        with setup.open_physics() as own:
            return replay_round(round_, graph, options, physics=own, open_sim=open_sim)
    rules_config = setup.rules_config()
    zones = setup.site_zones()
    filled = fill_missing(round_, zones, rules_config, options.missing)
    round_ = filled.round
    warnings = round_.warnings + _check_on_map(round_, graph, options.implausible)
    bomb = read_data_bomb(round_, zones, rules_config.plant_s) if options.bomb else None
    plan = snap_round(
        round_,
        graph,
        physics=physics,
        sites=carrier_sites(round_, bomb.carriers, zones) if bomb is not None else None,
        node_site=zones.site_of(graph.positions) if bomb is not None else None,
    )
    players = plan.players
    n = len(players)
    truth = data_deaths(round_, plan.plans)
    first = [int(p.target_frame[0]) if len(p.target_node) else 0 for p in plan.plans]
    start_nodes = np.array(
        [int(p.target_node[0]) if len(p.target_node) else 0 for p in plan.plans], dtype=np.int64
    )

    def at_first(array: np.ndarray, default: object) -> list:
        return [array[i, first[i]] if len(plan.plans[i].target_node) else default for i in range(n)]

    weapons = [w or "Knife" for w in at_first(np.asarray(round_.weapon), "Knife")]
    agents = Agents.create(
        names=[p.name for p in players],
        sides=[p.side for p in players],
        positions=graph.positions[start_nodes],
        nodes=start_nodes,
        weapons=weapons,
        hp=np.clip(at_first(np.asarray(round_.hp), 100), 1, 100),
        armor=np.clip(at_first(np.asarray(round_.armor), 0), 0, 100),
        helmet=np.asarray(at_first(np.asarray(round_.helmet), False), bool),
        has_defuser=np.asarray(at_first(np.asarray(round_.has_defuser), False), bool),
        yaw=np.nan_to_num(np.asarray(at_first(np.asarray(round_.yaw), 0.0), dtype=float)),
    )
    never = np.array([len(p.target_node) == 0 for p in plan.plans])
    agents.alive[never] = False
    agents.hp[never] = 0

    carrier = int(bomb.carriers[0]) if bomb is not None else -1  # the data's, if alive here
    if carrier >= 0 and not agents.alive[carrier]:
        carrier = -1
    plant = policy_plant(bomb, plan.plans) if bomb is not None else None
    defuse = defuse_windows(bomb) if bomb is not None else {}

    policy = PlanPolicy(plan.plans, tick_at, graph, plant, defuse, plan.caps)
    start_tick = int(frame_ticks[0])
    scripted = np.zeros(n, dtype=bool)
    weapon_frames = np.asarray(round_.weapon)
    kit_frames = np.asarray(round_.has_defuser, dtype=bool)
    present = np.asarray(round_.present, dtype=bool)
    alive_frames = np.asarray(round_.alive, dtype=bool)
    frame_of_tick = {int(t): f for f, t in enumerate(frame_ticks)}
    end_tick = int(frame_ticks[-1])
    with open_sim(
        setup,
        agents,
        policy,
        physics=physics,
        bomb_carrier=carrier,
        start_tick=start_tick,
        record_ticks=frame_ticks,
        seed=options.seed,
    ) as sim:
        if sim.combat is not None and not np.isin(agents.weapon, FIREARMS).any():
            warnings += ("shooting is on, but no player holds a firearm: nobody can shoot",)
        # The data's deaths are scripted at their time without shooting or with `deaths` "data";
        # with the fight deciding, a player the fight has not killed by `DEATH_WINDOW_S` after
        # its real death is taken out then (its data ends: nothing is left to replay).
        # From the real death to then the player holds no weapon (module docstring).
        grace = DEATH_WINDOW_S if sim.combat is not None and options.deaths == "simulated" else 0
        dying = [i for i, p in enumerate(plan.plans) if p.death_frame >= 0]
        deaths = {i: tick_at(truth.seconds[i] + grace) for i in dying}
        disarm = {i: tick_at(truth.seconds[i]) for i in dying} if grace else {}
        # The replay follows the data to its last frame: a round the rules end earlier (the
        # clock, the bomb) goes on moving through the round-end delay, as the real players
        # did, with the outcome as decided (`Simulator.step(after_end=True)`).
        # It plays event by event (`Simulator.run`) from one stop to the next: a frame's tick,
        # where the data's bomb, weapon and kit are followed, and the tick before a death.
        while sim.tick < end_tick and not (sim.done and sim.outcome is None):
            # Scripted deaths come before the step of the death frame's tick, which records the
            # frame: the frame that shows the player dead in the data shows it dead here too.
            for i, tick in deaths.items():
                if tick <= sim.tick + 1 and agents.alive[i]:
                    sim.kill(i, "scripted")
                    scripted[i] = True
            for i, tick in disarm.items():
                if tick <= sim.tick + 1:
                    sim.disarm(i)
            stop = int(frame_ticks[np.searchsorted(frame_ticks, sim.tick, side="right")])
            for i, tick in [*deaths.items(), *disarm.items()]:
                if agents.alive[i] and tick > sim.tick + 1:
                    stop = min(stop, tick - 1)
            sim.run(to_tick=max(stop, sim.tick + 1), after_end=True)
            f = frame_of_tick.get(sim.tick)
            if f is not None and bomb is not None:
                follow_data_bomb(sim, bomb, f, round_)
            if f is not None:  # follow the weapon in hand and the kit, as the data shows them
                for alive in np.nonzero(agents.alive)[0]:
                    i = int(alive)
                    if present[i, f]:
                        sim.equip(i, has_defuser=kit_frames[i, f])
                    if weapon_frames[i, f] and alive_frames[i, f]:  # the dead hold nothing
                        sim.equip(i, weapon=weapon_frames[i, f])
        played_from = sim.tick
        while sim.bomb.planter >= 0 and not sim.done:
            sim.step()  # a plant under way when the data ends completes (or aborts) first
        if options.play_out and sim.combat is not None and not sim.done:
            # the deaths the fight had until after the data's end (`grace`) come first
            for tick, i in sorted((t, i) for i, t in deaths.items() if agents.alive[i]):
                sim.run(to_tick=max(tick - 1, sim.tick))
                if sim.done:
                    break
                if agents.alive[i]:
                    sim.kill(i, "scripted")
                    scripted[i] = True
            # bounded: the clock ends the round at round_ticks, a bomb at most bomb_ticks later
            limit = max(sim.tick, rules_config.round_ticks) + rules_config.bomb_ticks + 1
            if not sim.done:
                sim.run(to_tick=limit)
        stuck = np.asarray(sim.mover.stuck_events).copy()
        recoveries = np.asarray(sim.mover.recoveries).copy()
    return ReplayResult(
        plan=plan,
        recording=_per_frame(sim.recording, frame_ticks),
        frame_ticks=frame_ticks,
        scripted_death=scripted,
        logs=policy.logs,
        outcome=sim.outcome,
        events=sim.events,
        stuck=stuck,
        recoveries=recoveries,
        played_out_s=(sim.tick - played_from) / TICK_RATE,
        warnings=warnings,
        inferred=filled.notes,
        contradictions=contradictions(round_),
        data_deaths=truth,
        bomb=bomb,
        utility=setup.utility.counts if setup.utility is not None and setup.shooting else None,
    )


def _frame_ticks(round_: Round) -> np.ndarray:
    """(F,) simulator tick of each data frame; an EstaError when the round cannot be replayed
    on one clock: no frames, no player in any frame, or two frames at the same time. Frames
    closer than a simulator tick (data parsed at 64 or 128 frames per second) share a tick."""
    where = f"{round_.path}: round {round_.round_num}"
    if len(round_.frame_seconds) == 0:
        raise EstaError(f"round {round_.round_num} has no frames (events only): nothing to replay")
    if round_.num_players == 0:
        raise EstaError(f"{where}: no player in any frame: nothing to replay")
    ticks = np.array([tick_at(s) for s in round_.frame_seconds], dtype=np.int64)
    repeated = np.flatnonzero(np.diff(round_.frame_seconds) <= 0)
    if len(repeated):
        k = int(repeated[0]) + 1
        raise EstaError(
            f"{where}: frame {k} ({float(round_.frame_seconds[k]):.3f} s) is not after frame "
            f"{k - 1}: frames must be at distinct times"
        )
    return ticks


def _per_frame(recording: Recording, frame_ticks: np.ndarray) -> Recording:
    """The recording with one sample per data frame: frames that share a simulator tick share
    its sample (the simulator records each tick once)."""
    if len(recording.ticks) == len(frame_ticks):
        return recording
    at = np.searchsorted(recording.ticks, frame_ticks)
    return replace(
        recording,
        ticks=frame_ticks,
        position=recording.position[at],
        yaw=recording.yaw[at],
        hp=recording.hp[at],
        alive=recording.alive[at],
    )


OFF_MAP_M = 10.0
"""How far outside the waypoints' bounding box an alive player may stand: six times the farthest
measured in the real rounds (1.7 m, a jump above the highest waypoint)."""


def _check_on_map(round_: Round, graph: WaypointGraph, policy: Implausible) -> tuple[str, ...]:
    """The first alive player far outside the map (module `OFF_MAP_M`) as a warning, or with
    the "fail" policy as an EstaError."""
    low = graph.positions.min(axis=0) - OFF_MAP_M
    high = graph.positions.max(axis=0) + OFF_MAP_M
    position = np.asarray(round_.position, dtype=np.float64)
    usable = np.asarray(round_.alive, bool) & np.isfinite(position).all(axis=2)
    outside = usable & ((position < low) | (position > high)).any(axis=2)
    if not outside.any():
        return ()
    p, f = first_offender(outside)
    x, y, z = position[p, f]
    problem = (
        f"frame {f}: {round_.players[p].name} at ({x:.1f}, {y:.1f}, {z:.1f}) m is more than "
        f"{OFF_MAP_M:g} m outside the map"
    )
    if policy == "fail":
        raise EstaError(f"{round_.path}: round {round_.round_num}: {problem}")
    return (problem,)
