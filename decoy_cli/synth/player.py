"""Play one scripted round in the simulator and record it as ESTA round data.

`play_round` opens the round through `decoy_cli.sim.setup` (`scripted_setup`: the kinematic
mover, the bomb, combat with a damage model once per frame), lets `ScriptedPolicy`
(decoy_cli/synth/policy.py) drive the agents, and records frames and events as ESTA round data
(decoy_cli/synth/recording.py). Whatever the simulator's rules say ends the round (elimination,
detonation, defuse, time); the winner and reason are the simulator's.
"""

from __future__ import annotations

from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass, field
from typing import cast

import numpy as np

from decoy_cli.esta.frames import Side
from decoy_cli.esta.records import EstaRoundRecord, PlayerRecord
from decoy_cli.geometry import facing_yaw
from decoy_cli.sim.combat import DamageModel
from decoy_cli.sim.engine import Simulator
from decoy_cli.sim.rules import SiteZones
from decoy_cli.sim.setup import RoundSetup, open_round
from decoy_cli.sim.state import Agents
from decoy_cli.synth.loadouts import START_VALUE, Loadout
from decoy_cli.synth.policy import ScriptedPolicy
from decoy_cli.synth.recording import (
    DEMO_TICK_RATE,
    FRAME_EVERY_TICKS,
    FREEZE_TIME_TICKS,
    RESTART_DELAY_TICKS,
    EventLog,
    Recorder,
)
from decoy_cli.synth.routes import Places, RoutePlan
from decoy_cli.waypoints.graph import WaypointGraph
from decoy_cli.world.physics import PhysicsWorld


@dataclass(frozen=True)
class Team:
    """The ten players of the match: names, steamIDs, sides (T first, then CT)."""

    names: tuple[str, ...]
    steam_ids: tuple[int, ...]
    sides: tuple[str, ...]


@dataclass
class PlayedRound:
    """A scripted round as played: the ESTA round data and what the script chose."""

    record: EstaRoundRecord
    plan: RoutePlan
    buys: dict[str, str]
    invalid_actions: int

    @property
    def end_seconds(self) -> float:
        """Seconds from freeze-time end to the round end."""
        return (self.record.end_tick - self.record.freeze_end_tick) / DEMO_TICK_RATE


@dataclass(frozen=True, kw_only=True)
class RoundScript:
    """What a scripted round is played from: the routes, the loadouts and the team."""

    places: Places
    plan: RoutePlan
    loadouts: list[Loadout]
    team: Team
    buys: dict[str, str] = field(default_factory=dict)


def scripted_setup(graph: WaypointGraph, damage_model: DamageModel | None) -> RoundSetup:
    """How scripted rounds are simulated: kinematic mover, bomb on, combat (with a damage
    model) once per recorded frame."""
    return RoundSetup(
        graph=graph,
        mover="kinematic",
        combat=damage_model is not None,
        bomb=True,
        damage_model=damage_model,
        combat_every_ticks=FRAME_EVERY_TICKS,
    )


def scripted_agents(graph: WaypointGraph, script: RoundScript) -> Agents:
    """The agents of a scripted round before its first tick: on their spawn waypoints, facing
    their first leg, with their loadouts."""
    plan, loadouts, team = script.plan, script.loadouts, script.team
    start_nodes = np.array([route[0].node for route in plan.routes], dtype=np.int64)
    positions = graph.positions[start_nodes]
    first_moves = [route[1].node if len(route) > 1 else route[0].node for route in plan.routes]
    yaw = facing_yaw(
        graph.positions[first_moves, 0] - positions[:, 0],
        graph.positions[first_moves, 1] - positions[:, 1],
    )
    return Agents.create(
        names=list(team.names),
        sides=list(team.sides),
        positions=positions,
        nodes=start_nodes,
        weapons=[lo.active for lo in loadouts],
        armor=np.array([lo.armor for lo in loadouts]),
        helmet=np.array([lo.helmet for lo in loadouts]),
        has_defuser=np.array([lo.defuse_kit for lo in loadouts]),
        yaw=yaw,
    )


@contextmanager
def open_scripted_round(
    setup: RoundSetup, script: RoundScript, *, seed: int, physics: PhysicsWorld | None = None
) -> Iterator[Simulator]:
    """The simulator of a scripted round before its first tick (policy `ScriptedPolicy`)."""
    policy = ScriptedPolicy(setup.graph, script.places, script.plan)
    agents = scripted_agents(setup.graph, script)
    with open_round(
        setup, agents, policy, physics=physics, bomb_carrier=script.plan.carrier, seed=seed
    ) as sim:
        yield sim


def play_round(
    setup: RoundSetup,
    script: RoundScript,
    *,
    round_num: int,
    start_tick: int,
    seed: int,
    physics: PhysicsWorld | None = None,
) -> PlayedRound:
    """Play one round of `script` and record it (demo ticks from `start_tick`).

    `physics` lends a pybullet world of the map for line of sight (without it, one is opened
    for the round when combat needs it).
    """
    graph, plan, loadouts, team = setup.graph, script.plan, script.loadouts, script.team
    n = len(plan.routes)
    zones = SiteZones.from_graph(graph)
    freeze_end = start_tick + FREEZE_TIME_TICKS
    with open_scripted_round(setup, script, seed=seed, physics=physics) as sim:
        agents = sim.agents
        recorder = Recorder(graph, zones, agents)
        events = EventLog(freeze_end, agents)
        recorder.snapshot(sim)
        while not sim.done:
            hp_before = agents.hp.copy()
            new = sim.step()
            events.add(sim, new, hp_before)
            if sim.tick % FRAME_EVERY_TICKS == 0:
                recorder.snapshot(sim)
    if sim.outcome is None:
        raise RuntimeError(f"round {round_num} did not end within the simulator's bound")

    end_tick = events.demo_tick(sim.outcome.tick)
    players = [
        PlayerRecord(
            name=team.names[i],
            steam_id=team.steam_ids[i],
            side=cast(Side, team.sides[i]),
            inventory=loadouts[i].inventory,
            equipment_value=loadouts[i].value,
            start_equipment_value=START_VALUE,
            cash_spent=max(0, loadouts[i].value - START_VALUE),
        )
        for i in range(n)
    ]
    frames = recorder.arrays()
    record = EstaRoundRecord(
        round_num=round_num,
        start_tick=start_tick,
        freeze_end_tick=freeze_end,
        end_tick=end_tick,
        end_official_tick=end_tick + RESTART_DELAY_TICKS,
        frame_ticks=np.array([events.demo_tick(t) for t in recorder.ticks], dtype=np.int64),
        players=players,
        winning_side=cast(Side, sim.outcome.winner),
        end_reason=sim.outcome.reason,
        bomb_plant_tick=events.plant_tick,
        damages=events.damages,
        kills=events.kills,
        bomb_events=events.bomb_events,
        **frames,
    )
    invalid = sum(1 for e in sim.events if e.kind == "invalid_action")
    return PlayedRound(record, plan, dict(script.buys), invalid)
