"""Replaying small rounds on the shipped de_dust2 graph: timing against the data's clock, fates
(survivors, scripted deaths, absent players), the weapon in hand, the bomb, and player metrics.

Rounds are duck-typed objects with the attributes of the ESTA reader's `Round` that the replay
reads. Players stand on real waypoints of the shipped graph, at 2 frames per second on a 128-tick
clock (frame j at tick 1000 + 64 j, freeze time ending 10 ticks before the first frame, as in
tests/esta_fixtures.py), so every data frame time lies between two simulator ticks.
"""

from __future__ import annotations

import math
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd
import pytest

from decoy_cli.csgo import HAMMER_TO_M
from decoy_cli.errors import EstaError
from decoy_cli.esta import Round, RoundClock
from decoy_cli.esta.frames import PlayerInfo
from decoy_cli.metrics import METRIC_NAMES, METRIC_NAMES_CLOCK, player_metrics
from decoy_cli.replay.lateness import LATE_CAUSES, stretch_causes
from decoy_cli.replay.plans import PlayerPlan
from decoy_cli.replay.replayer import ReplayOptions, ReplayResult, replay_round
from decoy_cli.replay.snapping import SnapStatus
from decoy_cli.sim.engine import Simulator
from decoy_cli.sim.rules import BOMB_TARGET_BOXES, RulesConfig, SiteZones
from decoy_cli.sim.setup import open_round
from decoy_cli.waypoints.build import builtin_graph
from decoy_cli.waypoints.graph import EdgeKind
from decoy_cli.weapons import max_speed_u_s
from decoy_cli.world.navmesh import nav_world
from decoy_cli.world.physics import PhysicsWorld

MOVERS = ("kinematic", "physics")
FRAME_STEP = 64  # data ticks between frames at 128 tick: 2 frames per second
DATA_TICK_RATE = 128
FIRST_TICK = 1000
FREEZE_END = 990
FRAME_S = FRAME_STEP / DATA_TICK_RATE

RUN_START = (5.458, -19.007, 0.008)
"""A T-spawn waypoint with a straight run of 40 walk edges north (into Outside Long)."""
STILL_SPOT = (-33.742, -20.407, 2.458)
"""A T-spawn waypoint far from the run, where players stand."""
DETOUR = ((-19.927, -9.13, 2.444), (-19.286, -7.701, 2.483))
"""Two T-spawn waypoints 1.57 m apart with 4.57 m of path between them (around an obstacle)."""
ABSENT_PARKING_NODE = 0
"""Where the replay puts an agent that is never on the graph (it has no waypoint of its own)."""

PLAYER_COLUMNS = (
    "player",
    "side",
    "died_original",
    "died_replay",
    "death",
    "targets",
    "late_share",
    "late_over_frame",
    "late_zigzag",
    "late_detour",
    "late_speed",
    "late_gap",
    "late_replay",
    "late_p95_s",
    "stuck",
    "recoveries",
    "relocations",
    *METRIC_NAMES,
    "reason",
)
"""The columns of `player_metrics`, in order (see its docstring)."""


@dataclass(frozen=True)
class Track:
    """One player in a generated round: a waypoint per frame (-1: not recorded in that frame)."""

    name: str
    side: str
    nodes: list[int]
    weapons: list[str] | str = "AK-47"
    dead_from: int | None = None  # first frame recorded dead (hp 0, lying where it died)
    bomb: bool | list[bool] = False  # holds the bomb: in every frame, or frame by frame
    offset: tuple[float, float, float] = (0.0, 0.0, 0.0)  # added to the waypoint position


def node_at(point: tuple[float, float, float]) -> int:
    """The shipped graph's waypoint at `point` (metres, to the millimetre)."""
    index, distance = builtin_graph().nearest(np.array([point]))
    assert index[0] >= 0 and distance[0] < 0.01, f"no waypoint at {point}"
    return int(index[0])


def straight_run(start: int, direction: int, count: int) -> list[int]:
    """`count` waypoints from `start` along walk edges of one compass direction."""
    graph = builtin_graph()
    run = [start]
    while len(run) < count:
        edge = int(graph.out_edges[run[-1], direction])
        assert edge >= 0 and graph.edge_kind[edge] == EdgeKind.WALK, "the run leaves the walks"
        run.append(int(graph.edge_target[edge]))
    return run


def frame_ticks(count: int) -> np.ndarray:
    return FIRST_TICK + FRAME_STEP * np.arange(count, dtype=np.int64)


def make_round(
    tracks: list[Track], ticks: np.ndarray | None = None, plant_frame: int | None = None
) -> Round:
    """A round with the reader's attributes; `plant_frame` sets a bomb plant 10 ticks before it."""
    frames = len(tracks[0].nodes) if ticks is None else len(ticks)
    ticks = frame_ticks(frames) if ticks is None else np.asarray(ticks, dtype=np.int64)
    positions = builtin_graph().positions
    n = len(tracks)
    position = np.full((n, frames, 3), np.nan)
    alive = np.zeros((n, frames), dtype=bool)
    weapon = np.full((n, frames), "", dtype=object)
    has_bomb = np.zeros((n, frames), dtype=bool)
    for p, track in enumerate(tracks):
        nodes = np.asarray(track.nodes, dtype=np.int64)
        assert nodes.shape == (frames,)
        here = nodes >= 0
        position[p, here] = positions[nodes[here]] + np.asarray(track.offset)
        alive[p] = here
        if track.dead_from is not None:
            position[p, track.dead_from :] = position[p, track.dead_from - 1]
            alive[p, track.dead_from :] = False
        names = [track.weapons] * frames if isinstance(track.weapons, str) else track.weapons
        weapon[p, alive[p]] = np.asarray(names, dtype=object)[alive[p]]
        has_bomb[p] = alive[p] & np.asarray(track.bomb, dtype=bool)
    present = np.isfinite(position).all(axis=2)
    return Round(
        match_id="made-up",
        map_name="de_dust2",
        path=Path("made-up.json"),
        round_num=1,
        tick_rate=DATA_TICK_RATE,
        players=[PlayerInfo(t.name, t.name, None, t.side) for t in tracks],
        frame_ticks=ticks,
        frame_seconds=RoundClock(FREEZE_END, DATA_TICK_RATE).seconds(ticks),
        clock=RoundClock(FREEZE_END, DATA_TICK_RATE),
        position=position,
        yaw=np.where(present, 90.0, np.nan),
        alive=alive,
        present=present,
        hp=np.where(alive, 100, np.where(present, 0, -1)).astype(np.int16),
        armor=np.where(present, 100, -1).astype(np.int16),
        helmet=present.copy(),
        has_defuser=np.zeros((n, frames), dtype=bool),
        weapon=weapon,
        has_bomb=has_bomb,
        vertical_speed=np.full((n, frames), np.nan),  # unknown, as in files without velocityZ
        bomb_plant_tick=None if plant_frame is None else int(ticks[plant_frame]) - 10,
        bomb_planted=np.arange(frames) >= (frames if plant_frame is None else plant_frame),
        bomb_position=np.full((frames, 3), np.nan),
        bombsite=np.full(frames, ""),
        bomb_events=pd.DataFrame(),
        damages=pd.DataFrame(),
        kills=pd.DataFrame(),
        flashes=pd.DataFrame(),
        winning_side=None,
        end_reason=None,
        start_tick=None,
        end_tick=None,
    )


def sim_tick(seconds: float) -> int:
    """The simulator tick of a data time (60 Hz, from freeze-time end)."""
    return round(seconds * 60)


@pytest.fixture(scope="module")
def physics() -> Iterator[PhysicsWorld]:
    with PhysicsWorld(nav_world()) as world:
        yield world


def replay(round_: Round, physics: PhysicsWorld, mover: str, bomb: bool = True) -> ReplayResult:
    """Replay with combat off (deaths in the data are scripted)."""
    options = ReplayOptions(combat=False, bomb=bomb, mover=mover)
    return replay_round(round_, builtin_graph(), options, physics=physics)


# ---- timing: standing, walking, running late --------------------------------------------------

TIMING_FRAMES = 21  # 10 s
Timed = tuple[Round, ReplayResult]
STILL, WALKER, DETOURER = range(3)


def timing_round() -> Round:
    """One player stands 10 s; one walks the straight run, two edges per frame (2.8 m/s, below
    the AK-47's 4.1 m/s); one runs the detour there and back in one frame each (4.57 m in 0.5 s:
    over twice the AK-47's speed), then stands still."""
    run = straight_run(node_at(RUN_START), direction=0, count=2 * TIMING_FRAMES - 1)
    a, b = node_at(DETOUR[0]), node_at(DETOUR[1])
    return make_round(
        [
            Track("still", "T", [node_at(STILL_SPOT)] * TIMING_FRAMES),
            Track("walker", "T", run[::2]),
            Track("detourer", "T", [a, b, a] + [a] * (TIMING_FRAMES - 3)),
        ]
    )


@pytest.fixture(scope="module", params=MOVERS)
def timed(request: pytest.FixtureRequest, physics: PhysicsWorld) -> Timed:
    round_ = timing_round()
    return round_, replay(round_, physics, request.param)


def test_a_standing_player_stays_put_alive_and_on_time(timed: Timed) -> None:
    round_, result = timed
    rec = result.recording
    drift = np.linalg.norm(rec.position[:, STILL] - round_.position[STILL], axis=1)
    assert drift.shape == (TIMING_FRAMES,) and drift.max() <= 0.05
    assert rec.alive[:, STILL].all()
    assert np.array_equal(result.logs[STILL].lateness_s, np.zeros(TIMING_FRAMES))
    assert result.plan.plans[STILL].stop_seconds == pytest.approx(10.0)


def test_a_feasible_walk_arrives_on_time_at_every_target(timed: Timed) -> None:
    round_, result = timed
    plan = result.plan.plans[WALKER]
    assert plan.num_infeasible == 0 and plan.worst_ratio < 1.0
    assert np.array_equal(result.logs[WALKER].lateness_s, np.zeros(TIMING_FRAMES))
    # The recorded frame is one tick after the arrival at most: within 0.1 m of the target.
    error = np.linalg.norm(result.recording.position[:, WALKER] - round_.position[WALKER], axis=1)
    assert error.max() <= 0.1
    assert result.recording.alive[:, WALKER].all()


def test_a_plan_twice_too_fast_runs_late_then_catches_up(timed: Timed) -> None:
    round_, result = timed
    plan = result.plan.plans[DETOURER]
    assert plan.interval_infeasible[:2].all() and plan.interval_speed_ratio[:2].min() >= 2.0
    late = result.logs[DETOURER].lateness_s
    assert np.all(np.isfinite(late))  # every target is reached
    assert late[0] == 0.0 and 0.0 < late[1] < late[2]  # lateness piles up over the two runs
    assert late[3] > 0.0  # still late at the first target of the standing period ...
    assert np.array_equal(late[4:], np.zeros(TIMING_FRAMES - 4))  # ... then on time again
    stand = np.linalg.norm(
        result.recording.position[4:, DETOURER] - round_.position[DETOURER, 4:], axis=1
    )
    assert stand.max() <= 0.05
    row = result.lateness_table().iloc[DETOURER]
    assert row["late_max_s"] == pytest.approx(late.max())
    assert row["late_over_frame"] == int(np.sum(late > 0.5 + 1e-9))
    assert row["late_share"] == pytest.approx(3 / TIMING_FRAMES)
    # why: the stretch of late targets began where the plan asked for more than the cap, only
    # by the graph's way round the wall (the straight line would be in time); every late
    # target of the stretch is put down to that
    cause = stretch_causes(plan, result.plan.caps[DETOURER], late)
    over = late > 0.5 + 1e-9
    assert set(cause[over].tolist()) == {LATE_CAUSES.index("detour")}
    assert plan.interval_detour[:2].all() and not plan.interval_detour[2:].any()
    assert row["late_detour"] == row["late_over_frame"] >= 1
    assert row["late_speed"] == row["late_gap"] == row["late_zigzag"] == row["late_replay"] == 0


def test_a_late_stretch_is_put_down_to_how_its_first_interval_compares_with_the_cap(
    timed: Timed,
) -> None:
    _, result = timed
    plan = result.plan.plans[DETOURER]
    late = result.logs[DETOURER].lateness_s
    caps = result.plan.caps[DETOURER]
    stretch = late > 1 / 60 + 1e-9
    first = int(np.flatnonzero(stretch)[0])  # the stretch's first target

    def cause_of(plan_: PlayerPlan, caps_: np.ndarray) -> set[str]:
        return {LATE_CAUSES[c] for c in stretch_causes(plan_, caps_, late)[stretch]}

    assert cause_of(plan, caps) == {"detour"}
    assert np.all(stretch_causes(plan, caps, late)[~stretch] == -1)
    assert cause_of(plan, caps * 100) == {"replay"}  # the cap allowed it: the replay's delay
    tiny = caps.copy()
    tiny[first - 1] = 1e-3  # not even the straight line fits
    assert cause_of(plan, tiny) == {"speed"}
    zigzag = replace(
        plan,
        interval_length_m=plan.interval_straight_m * 1.05,
        interval_run_m=plan.interval_straight_m * 1.05,  # no ladder: all of it is run
        interval_required_speed_m_s=caps * 2,
    )
    assert cause_of(zigzag, caps) == {"zigzag"}
    gap = replace(plan, interval_unreachable=np.ones_like(plan.interval_unreachable))
    assert cause_of(gap, caps) == {"gap"}


def test_a_late_target_is_put_down_to_the_interval_that_added_most_lateness_in_its_stretch(
    timed: Timed,
) -> None:
    _, result = timed
    plan = result.plan.plans[DETOURER]
    caps = result.plan.caps[DETOURER].copy()
    assert plan.interval_detour[1] and len(plan.target_node) >= 7
    caps[0] = 1e3  # the first interval within the cap: lateness there is the replay's own
    late = np.zeros(len(plan.target_node))
    late[1:4] = [0.05, 1.0, 0.8]  # a small delay, then the detour adds most, then catch-up
    late[5] = 0.6  # a second stretch, on a standing interval within the cap
    names = [LATE_CAUSES[c] if c >= 0 else "" for c in stretch_causes(plan, caps, late)]
    assert names[:7] == ["", "replay", "detour", "detour", "", "replay", ""]


def test_survivors_survive_and_the_round_is_undecided(timed: Timed) -> None:
    _, result = timed
    assert result.recording.alive[-1].all()
    assert not result.scripted_death.any()
    assert result.outcome is None and result.events == []
    assert not np.asarray(result.stuck).any() and not np.asarray(result.recoveries).any()


def test_the_recording_is_at_the_data_frame_clock(timed: Timed) -> None:
    round_, result = timed
    expected = np.array([round(s * 60) for s in round_.frame_seconds])
    assert np.array_equal(result.recording.ticks, expected)
    assert np.array_equal(result.frame_ticks, expected)
    assert result.recording.position.shape == (TIMING_FRAMES, 3, 3)


@pytest.mark.parametrize("mover", MOVERS)
def test_an_irregular_frame_clock_is_recorded_as_it_is(physics: PhysicsWorld, mover: str) -> None:
    """Frames 0.5 s apart with one missing frame and one off the 64-tick grid."""
    ticks = np.array([1000, 1064, 1128, 1256, 1320, 1449], dtype=np.int64)
    run = straight_run(node_at(RUN_START), direction=0, count=len(ticks))
    round_ = make_round([Track("walker", "T", run)], ticks=ticks)
    result = replay(round_, physics, mover)
    expected = [round(s * 60) for s in (ticks - FREEZE_END) / DATA_TICK_RATE]
    assert expected[-1] == 215  # (1449 - 990) / 128 s = 3.586 s = 215.16 ticks
    assert result.recording.ticks.tolist() == expected
    error = np.linalg.norm(result.recording.position[:, 0] - round_.position[0], axis=1)
    assert error.max() <= 0.1


def test_frames_at_the_demo_tick_rate_share_simulator_ticks(physics: PhysicsWorld) -> None:
    """A walk at 3 m/s parsed at every tick of a 128-tick demo (3 s, 384 frames): frames closer
    than a simulator tick share its sample, and the replay keeps time with them."""
    frames = 3 * DATA_TICK_RATE
    ticks = FIRST_TICK + np.arange(frames, dtype=np.int64)
    run = straight_run(node_at(RUN_START), direction=0, count=14)
    metres = 3.0 * (ticks - FIRST_TICK) / DATA_TICK_RATE
    round_ = make_round([Track("walker", "T", [run[int(m / 0.7)] for m in metres])], ticks=ticks)
    result = replay(round_, physics, "kinematic", bomb=False)
    sim_ticks = np.array([sim_tick(s) for s in round_.frame_seconds])
    assert len(np.unique(sim_ticks)) < frames  # some frames share a simulator tick
    assert result.recording.ticks.tolist() == sim_ticks.tolist()
    assert result.recording.position.shape == (frames, 1, 3)
    shared = np.flatnonzero(np.diff(sim_ticks) == 0)
    assert np.array_equal(result.recording.position[shared], result.recording.position[shared + 1])
    lateness = result.lateness_table()
    assert lateness["late_over_frame"].tolist() == [0]
    error = np.linalg.norm(result.recording.position[:, 0] - round_.position[0], axis=1)
    assert error.max() <= 0.75


# ---- fates: scripted deaths, players who vanish, absent players --------------------------------

FATE_FRAMES = 12
DEATH_FRAME = 6
ALIVE, DIES, VANISHES, ABSENT, CT = range(5)


def fate_round() -> Round:
    """A survivor, a walker killed in the data at frame 6, a player who is no longer recorded
    after frame 4 (not killed: it vanishes), a CT who is never recorded, and a CT who stands."""
    run = straight_run(node_at(RUN_START), direction=0, count=FATE_FRAMES)
    a, b = node_at(DETOUR[0]), node_at(DETOUR[1])
    return make_round(
        [
            Track("alive", "T", [node_at(STILL_SPOT)] * FATE_FRAMES),
            Track("dies", "T", run, dead_from=DEATH_FRAME),
            Track("vanishes", "T", [a] * 5 + [-1] * (FATE_FRAMES - 5)),
            Track("absent", "CT", [-1] * FATE_FRAMES),
            Track("ct", "CT", [b] * FATE_FRAMES, weapons="M4A4"),
        ]
    )


@pytest.mark.parametrize("mover", MOVERS)
def test_data_deaths_are_scripted_and_absent_players_dead_from_the_start(
    physics: PhysicsWorld, mover: str
) -> None:
    round_ = fate_round()
    result = replay(round_, physics, mover)
    alive = result.recording.alive
    assert np.array_equal(alive[:, DIES], np.arange(FATE_FRAMES) < DEATH_FRAME)
    assert np.all(result.recording.hp[DEATH_FRAME:, DIES] == 0)
    assert not alive[:, ABSENT].any()
    assert alive[:, [ALIVE, VANISHES, CT]].all()  # a player who vanishes is not killed
    assert result.scripted_death.tolist() == [False, True, False, False, False]
    deaths = [e for e in result.events if e.kind == "death"]
    assert [(e.agent, e.data["reason"]) for e in deaths] == [(DIES, "scripted")]
    death_tick = result.frame_ticks[DEATH_FRAME]
    assert death_tick - 1 <= deaths[0].tick <= death_tick
    assert result.outcome is None

    table = player_metrics(round_, result.trace())
    assert table["died_original"].tolist() == [False, True, False, False, False]
    assert table["died_replay"].tolist() == [False, True, False, False, False]
    assert table["death"].tolist() == ["", "scripted", "", "", ""]
    assert table.loc[ABSENT, "reason"] == "original alive in fewer than 2 frames"
    assert table.loc[[ALIVE, DIES, VANISHES, CT], "reason"].isna().all()


def test_a_frame_the_data_says_is_in_the_air_is_not_a_target(physics: PhysicsWorld) -> None:
    """awpy's velocityZ is 0 on the ground: a frame with a vertical speed is in the air even
    where its height alone (a hop over a low box) does not tell."""
    run = straight_run(node_at(RUN_START), direction=0, count=2 * 9 - 1)[::2]
    round_ = make_round([Track("hopper", "T", run)])
    round_.vertical_speed[0] = 0.0
    round_.vertical_speed[0, 4] = 2.5
    result = replay(round_, physics, "kinematic")
    status = result.plan.snaps[0].status
    assert status[4] == SnapStatus.AIRBORNE
    assert (np.delete(status, 4) == SnapStatus.SNAPPED).all()


def test_a_jump_targets_the_floor_under_it(physics: PhysicsWorld) -> None:
    """A frame 1 m above the floor (a jump) is not snapped; the waypoint under it is a soft
    target, on the walker's way: it passes under the jump on time, instead of being sent to
    some floor near the jump."""
    run = straight_run(node_at(RUN_START), direction=0, count=2 * 9 - 1)[::2]
    round_ = make_round([Track("jumper", "T", run)])
    round_.position[0, 4, 2] += 1.0
    result = replay(round_, physics, "kinematic")
    status = result.plan.snaps[0].status
    assert status[4] == SnapStatus.AIRBORNE
    assert (np.delete(status, 4) == SnapStatus.SNAPPED).all()
    plan = result.plan.plans[0]
    assert plan.target_frame.tolist() == list(range(len(run)))
    assert plan.target_node[4] == run[4]
    assert np.nanmax(result.logs[0].lateness_s) == 0
    replayed = result.recording.position[4, 0]
    np.testing.assert_allclose(replayed[:2], round_.position[0, 4, :2], atol=0.15)


def test_an_absent_player_blocks_nobody(physics: PhysicsWorld) -> None:
    """A capsule mover must not keep a body for an agent that is dead from the start: a walker
    crossing the spot where the absent player is put arrives on time."""
    # from the east onto the parking node (node 0, a wall node at the west edge of the map)
    line = straight_run(ABSENT_PARKING_NODE, direction=2, count=6)[::-1]
    frames = len(line) + 2
    round_ = make_round(
        [Track("walker", "T", line + [line[-1]] * 2), Track("absent", "T", [-1] * frames)]
    )
    result = replay(round_, physics, "physics")
    parked = result.recording.position[0, 1]
    assert np.allclose(parked, builtin_graph().positions[ABSENT_PARKING_NODE])
    assert np.array_equal(result.logs[0].lateness_s, np.zeros(frames))
    error = np.linalg.norm(result.recording.position[:, 0] - round_.position[0], axis=1)
    assert error.max() <= 0.1
    assert result.stuck.tolist() == [0, 0]


# ---- the weapon in hand ------------------------------------------------------------------------


def expected_detour_lateness(weapon: str) -> float:
    """Lateness of one detour run in one frame, by the interval cap of `interval_caps`: the
    larger of the weapon's speed and the player's straight-line speed, times the path's zig-zag
    factor (at most 1.3)."""
    graph = builtin_graph()
    a, b = node_at(DETOUR[0]), node_at(DETOUR[1])
    path = graph.shortest_path(a, b)
    length = float(np.linalg.norm(np.diff(graph.positions[path], axis=0), axis=1).sum())
    straight = float(np.linalg.norm(graph.positions[b] - graph.positions[a]))
    cap = max(max_speed_u_s(weapon) * HAMMER_TO_M, straight / FRAME_S) * min(length / straight, 1.3)
    return length / cap - FRAME_S


@pytest.mark.parametrize("mover", MOVERS)
def test_the_weapon_in_hand_follows_the_data(physics: PhysicsWorld, mover: str) -> None:
    """The detour with an AWP in hand (3.8 m/s), then back with the knife out (4.8 m/s)."""
    simulators: list[Simulator] = []
    initial_weapons: list[list[str]] = []

    @contextmanager
    def watched_round(*args: Any, **kwargs: Any) -> Iterator[Simulator]:
        with open_round(*args, **kwargs) as sim:
            simulators.append(sim)
            initial_weapons.append(list(sim.agents.weapon))
            yield sim

    a, b = node_at(DETOUR[0]), node_at(DETOUR[1])
    weapons = ["AWP"] * 4 + ["Knife"] * 6
    round_ = make_round([Track("switcher", "T", [a] + [b] * 5 + [a] * 4, weapons=weapons)])
    options = ReplayOptions(combat=False, mover=mover)
    result = replay_round(round_, builtin_graph(), options, physics=physics, open_sim=watched_round)

    speeds = result.plan.plans[0].interval_max_speed_m_s
    assert speeds.tolist() == pytest.approx([3.81] * 4 + [4.7625] * 5)
    late = result.logs[0].lateness_s
    awp, knife = expected_detour_lateness("AWP"), expected_detour_lateness("Knife")
    assert awp - knife > 0.15
    tick = 1 / 60
    assert awp - tick <= late[1] <= awp + 2 * tick
    assert knife - tick <= late[6] <= knife + 2 * tick
    assert initial_weapons == [["AWP"]] and list(simulators[0].agents.weapon) == ["Knife"]


# ---- the bomb ----------------------------------------------------------------------------------

BOMB_FRAMES = 16
PLANT_FRAME = 12


def site_a_nodes() -> list[int]:
    """Two waypoints inside the measured bomb-target box of site A, more than 1 m apart."""
    graph = builtin_graph()
    low, high = BOMB_TARGET_BOXES["de_dust2"]["A"]
    inside = np.flatnonzero(np.all((graph.positions >= low) & (graph.positions <= high), axis=1))
    first = int(inside[len(inside) // 2])
    far = inside[np.linalg.norm(graph.positions[inside] - graph.positions[first], axis=1) > 1.0]
    nodes = [first, int(far[0])]
    assert (SiteZones.from_graph(graph).site_of(graph.positions[nodes]) == "A").all()
    return nodes


BOMB_KINDS = {"plant_begin", "plant", "plant_abort", "bomb_drop", "bomb_pickup", "explode"}


@pytest.mark.parametrize("mover", MOVERS)
def test_the_carrier_plants_in_site_a_before_the_data_does(
    physics: PhysicsWorld, mover: str
) -> None:
    """Two T stand in site A; the second carries the bomb and plants it."""
    spot, carrier_spot = site_a_nodes()
    round_ = make_round(
        [
            Track("mate", "T", [spot] * BOMB_FRAMES),
            Track("carrier", "T", [carrier_spot] * BOMB_FRAMES, bomb=True),
        ],
        plant_frame=PLANT_FRAME,
    )
    result = replay(round_, physics, mover)
    bomb = [(e.kind, e.agent, e.data.get("site")) for e in result.events if e.kind in BOMB_KINDS]
    assert bomb == [("plant_begin", 1, "A"), ("plant", 1, "A")]
    begin, plant = (e.tick for e in result.events if e.kind in BOMB_KINDS)
    assert plant - begin == RulesConfig().plant_ticks
    data_plant_s = (round_.bomb_plant_tick - FREEZE_END) / DATA_TICK_RATE
    assert plant <= sim_tick(data_plant_s)
    assert result.outcome is None  # a planted bomb stops the clock; the data ends first

    without = replay(round_, physics, mover, bomb=False)
    assert without.events == []
    assert np.array_equal(without.recording.position, result.recording.position)


@pytest.mark.parametrize("mover", MOVERS)
def test_the_bomb_changes_hands_and_is_planted_when_the_data_says(
    physics: PhysicsWorld, mover: str
) -> None:
    """The data's carrier changes (a pass in site A): the replay hands the bomb over, and the
    new carrier begins planting at the data's plant start (plant tick minus the 3.0 s the rules
    take) and holds still until the plant completes."""
    spot, carrier_spot = site_a_nodes()
    first = [k < 2 for k in range(BOMB_FRAMES)]
    round_ = make_round(
        [
            Track("first", "T", [spot] * BOMB_FRAMES, bomb=first),
            Track("second", "T", [carrier_spot] * BOMB_FRAMES, bomb=[not k for k in first]),
        ],
        plant_frame=PLANT_FRAME,
    )
    result = replay(round_, physics, mover)
    bomb = [(e.kind, e.agent) for e in result.events if e.kind in (*BOMB_KINDS, "bomb_pickup")]
    assert bomb == [("bomb_pickup", 1), ("plant_begin", 1), ("plant", 1)]
    pickup, begin, plant = (e.tick for e in result.events if e.kind in (*BOMB_KINDS, "bomb_pickup"))
    assert pickup == result.frame_ticks[2]  # the first frame that shows the second holding it
    data_plant_s = (round_.bomb_plant_tick - FREEZE_END) / DATA_TICK_RATE
    rules = RulesConfig()
    assert abs(begin - sim_tick(data_plant_s - rules.plant_s)) <= 1
    assert plant - begin == rules.plant_ticks


def test_a_carrier_outside_the_sites_does_not_plant_and_drops_the_bomb(
    physics: PhysicsWorld,
) -> None:
    spot = node_at(STILL_SPOT)
    round_ = make_round(
        [
            Track("mate", "T", [node_at(DETOUR[0])] * BOMB_FRAMES),
            Track("carrier", "T", [spot] * BOMB_FRAMES, bomb=True, dead_from=PLANT_FRAME + 1),
        ],
        plant_frame=PLANT_FRAME,
    )
    result = replay(round_, physics, "kinematic")
    assert [(e.kind, e.agent) for e in result.events] == [("death", 1), ("bomb_drop", 1)]
    assert result.events[1].data["position"] == pytest.approx(
        builtin_graph().positions[spot].tolist()
    )


# ---- metrics and errors ------------------------------------------------------------------------

SNAP_OFFSET_M = 0.2


@pytest.mark.parametrize("mover", MOVERS)
def test_a_perfect_replay_of_a_standing_player_measures_the_snap_error(
    physics: PhysicsWorld, mover: str
) -> None:
    """One player stands 0.2 m east of a waypoint, one exactly on another."""
    frames = 10
    round_ = make_round(
        [
            Track("beside", "T", [node_at(STILL_SPOT)] * frames, offset=(SNAP_OFFSET_M, 0, 0)),
            Track("on", "T", [node_at(DETOUR[0])] * frames),
        ]
    )
    result = replay(round_, physics, mover)
    snap = result.plan.snaps[0]
    assert snap.error_m == pytest.approx(np.full(frames, SNAP_OFFSET_M))
    table = player_metrics(round_, result.trace())
    assert tuple(table.columns) == PLAYER_COLUMNS
    for name in METRIC_NAMES_CLOCK:
        assert table.loc[0, name] == pytest.approx(SNAP_OFFSET_M, abs=1e-9), name
        assert table.loc[1, name] == pytest.approx(0.0, abs=1e-9), name
    assert table.loc[0, "paper_rmse"] == pytest.approx(SNAP_OFFSET_M / math.sqrt(3), abs=1e-9)
    assert table[["late_share", "late_p95_s"]].to_numpy().tolist() == [[0.0, 0.0]] * 2
    assert table["late_over_frame"].tolist() == [0, 0] and (table["targets"] == frames).all()
    assert table[["stuck", "recoveries", "relocations"]].to_numpy().sum() == 0
    assert table["reason"].isna().all()


def test_a_round_without_frames_is_an_error(physics: PhysicsWorld) -> None:
    round_ = make_round([Track("t1", "T", [])], ticks=np.zeros(0, dtype=np.int64))
    with pytest.raises(EstaError, match="round 1 has no frames"):
        replay(round_, physics, "kinematic")


class Misses:
    """Test damage model: every visible pair misses (combat runs, nobody is hurt)."""

    def __call__(self, batch, rng: np.random.Generator):
        from decoy_cli.sim.combat import DamageResult

        none = np.zeros(len(batch), dtype=np.int64)
        return DamageResult(damage=none, hit_group=none - 1, hit=none.astype(bool))


@pytest.mark.parametrize("play_out", [True, False])
def test_an_undecided_round_is_played_out(physics: PhysicsWorld, play_out: bool) -> None:
    """The data ends (10 s) with a T in T spawn and a CT in CT spawn, both alive, no plant:
    played on, the clock ends the round at 115 s for the CT; not played on, it is undecided."""
    frames = 21
    ct_spot = int(builtin_graph().region_of("ct_spawn")[0])
    round_ = make_round(
        [
            Track("t", "T", [node_at(STILL_SPOT)] * frames),
            Track("ct", "CT", [ct_spot] * frames, weapons="M4A4"),
        ]
    )
    options = ReplayOptions(combat=True, damage_model=Misses(), play_out=play_out)
    result = replay_round(round_, builtin_graph(), options, physics=physics)
    assert result.recording.alive.all()  # the recording stays at the data's frames
    if play_out:
        assert (result.outcome.winner, result.outcome.reason) == ("CT", "TargetSaved")
        assert result.played_out_s == pytest.approx(115.0 - round_.frame_seconds[-1], abs=0.1)
    else:
        assert result.outcome is None and result.played_out_s == 0.0
