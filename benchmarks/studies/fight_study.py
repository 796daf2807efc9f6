"""Where the simulated fights of real rounds of both teams part from the real ones.

    python benchmarks/studies/fight_study.py FILE|FOLDER... [--models rules] [--mesh MESH.tri]
        [--seed S] [--sight-mesh MESH.tri]

For every real firearm kill of the rounds (both teams in the frames):

* line of sight between the two players' eyes at the kill (the kill event's x/y, the frame's z)
  in the map's nav-mesh world, and in `--mesh` (e.g. the brush mesh of ../shared/data/meshes);
  and at any of the real frames in the 3 s before it: what a replay on the real paths, which
  passes through the frames, can see at best between frames as sparse as these; and in a replay
  whose deaths follow the data (`--deaths data`: everybody on his real path until his real
  death), whether its combat steps ever found the victim in sight of the real killer, or of
  any enemy, from 3 s before the kill to half a second after: no fight can kill him otherwise;
* the DIP's decision for the pair there, with the attacker's yaw along its motion (as the replay
  has it) and aimed at the victim;
* what the replay (`--deaths simulated`) did: the victim killed by the fight within 3 s,
  earlier, later or never, and whether the real killer was dead by then or never hit him.

For every kill of that replay's fight: whether it reproduces a real death (within 3 s) or not
(the victim survived, or died more than 3 s away), and whether the two players saw each other
at a real frame within 1 s of it in each world: the fight's kills that are wrong and that
reality's geometry would have prevented.

Then the damage over all rounds, per player-frame alive in the data and the replay (a frame to
the next; a player-second at 1 frame/s): in how many the player lost HP in the data and in how
many the replay's fight damaged him, in all, by how many enemies see him at the frame (real
positions, nav world) and by how far the nearest of them is; and the HP real victims had one
frame before they died (how fast real fights end). Nothing here is timed.
"""

from __future__ import annotations

import argparse
import collections
from contextlib import contextmanager
from pathlib import Path

import numpy as np

from decoy_cli.csgo import TICK_RATE
from decoy_cli.damage import load_damage_model
from decoy_cli.esta import RoundFailure, collect_match_files, iter_rounds
from decoy_cli.geometry import eye_point, facing_yaw
from decoy_cli.metrics.kills import DEATH_WINDOW_S
from decoy_cli.modeling.fight_threshold import enemies_in_sight
from decoy_cli.replay.deaths import replay_deaths
from decoy_cli.replay.missing import fill_missing
from decoy_cli.replay.replayer import ReplayOptions, replay_round
from decoy_cli.sim.combat import CombatBatch
from decoy_cli.sim.rules import RulesConfig, SiteZones
from decoy_cli.sim.setup import open_round
from decoy_cli.waypoints.build import builtin_graph, graph_world
from decoy_cli.weapons import FIREARMS
from decoy_cli.world.meshfile import read_mesh
from decoy_cli.world.occlusion import read_sight_scene
from decoy_cli.world.physics import PhysicsWorld


def dip_hits(model, attacker, victim, a_pos, v_pos, yaw, weapon) -> bool:
    batch = CombatBatch(
        np.array([attacker]),
        np.array([victim]),
        a_pos[None],
        v_pos[None],
        np.array([yaw]),
        np.array([0.0]),
        np.array([100], np.int16),
        np.array([100], np.int16),
        np.array([weapon], dtype=object),
        np.array([100], np.int16),
        np.array([True]),
        "de_dust2",
    )
    return bool(model.decision.hit_probability(batch)[0] >= model.decision.threshold)


def sightings(round_, graph, model, sight) -> list[tuple[float, set[tuple[int, int]]]]:
    """(seconds, visible ordered pairs) of every combat step of a replay of `round_` whose
    deaths follow the data."""
    steps: list[tuple[float, set[tuple[int, int]]]] = []

    @contextmanager
    def watching(*args, **kwargs):
        with open_round(*args, **kwargs) as sim:
            if sim.combat is not None:
                step = sim.combat.run

                def run(agents, tick, rng):
                    pairs = sim.combat.los.visible_pairs(agents)
                    steps.append(
                        (
                            tick / TICK_RATE,
                            set(zip(pairs.attacker.tolist(), pairs.victim.tolist(), strict=True)),
                        )
                    )
                    return step(agents, tick, rng)

                sim.combat.run = run
            yield sim

    options = ReplayOptions(damage_model=model, deaths="data", sight=sight)
    replay_round(round_, graph, options, open_sim=watching)
    return steps


SIGHT_BUCKETS = 3
"""Enemies in sight counted 0, 1, 2 or more."""
DISTANCE_BANDS_M = (10.0, 20.0, 30.0)
"""Bands of the nearest enemy in sight: under 10 m, 10-20, 20-30, 30 m and more."""


def _damage_by_sight(round_, result, world, by_sight, by_distance) -> None:
    """Add the round's player-frames (a frame to the next, the player alive in the data and the
    replay, his position and both HP known) to `by_sight[enemies in sight at the frame]` =
    [count, lost HP in the data, damaged by the replay's fight], and those with an enemy in
    sight to `by_distance[band of the nearest such enemy]`."""
    hp = round_.hp.astype(float)
    present = np.asarray(round_.present, bool)
    alive = np.asarray(round_.alive, bool) & present
    replay_alive = result.recording.alive.T  # one row per data frame (replay_round)
    damaged = np.zeros(alive.shape, bool)
    for event in result.events:
        if event.kind == "damage":  # on the simulator's clock, as the frames' ticks
            frame = int(np.searchsorted(result.frame_ticks, event.tick, side="right")) - 1
            if 0 <= frame < alive.shape[1]:
                damaged[int(event.other), frame] = True
    known_next = np.zeros(alive.shape, bool)  # no frame after the last
    known_next[:, :-1] = present[:, 1:] & (hp[:, 1:] >= 0) & (hp[:, :-1] >= 0)
    watched = alive & replay_alive & known_next
    for frame, victim, enemies in enemies_in_sight(round_, world, watched):
        lost = not alive[victim, frame + 1] or hp[victim, frame + 1] < hp[victim, frame]
        counts = [by_sight[min(len(enemies), SIGHT_BUCKETS - 1)]]
        if len(enemies):
            delta = round_.position[enemies, frame] - round_.position[victim, frame]
            nearest = float(np.linalg.norm(delta, axis=1).min())
            band = int(np.searchsorted(DISTANCE_BANDS_M, nearest, side="right"))
            counts.append(by_distance[band])
        for row in counts:
            row[0] += 1
            row[1] += lost
            row[2] += bool(damaged[victim, frame])


def _shares(label: str, row: list[int]) -> str:
    """A line of `_damage_by_sight`'s table: player-frames, and the shares (counts) damaged in
    the data and by the replay's fight."""
    frames, real, replay = row
    return (
        f"  {label}: {frames} player-frames, data {real / frames:.3f} ({real}), "
        f"replay's fight {replay / frames:.3f} ({replay})"
    )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("inputs", nargs="+", type=Path)
    parser.add_argument("--models", default="rules")
    parser.add_argument("--mesh", type=Path)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--sight-mesh", type=Path, help="line of sight of the replays in it")
    args = parser.parse_args()
    graph = builtin_graph()
    sight = None
    if args.sight_mesh:  # the replays' line of sight (evaluate's --sight-mesh)
        sight = read_sight_scene(args.sight_mesh, graph.positions, "de_dust2")
    zones = SiteZones.from_graph(graph)
    model = load_damage_model(args.models)
    worlds = {"nav world": PhysicsWorld(graph_world(graph))}
    if args.mesh:
        worlds[args.mesh.name] = PhysicsWorld(read_mesh(args.mesh))
    seen = collections.Counter()
    seen_frames = collections.Counter()
    in_sight = collections.Counter()
    hp_before_death = []
    dip = collections.Counter()
    fates = collections.Counter()
    fight_kills = collections.Counter()
    kills = 0
    by_sight: dict[int, list[int]] = collections.defaultdict(lambda: [0, 0, 0])
    by_distance: dict[int, list[int]] = collections.defaultdict(lambda: [0, 0, 0])
    files, _ = collect_match_files(args.inputs)
    for round_ in iter_rounds(files, map_name="de_dust2"):
        if isinstance(round_, RoundFailure) or len(round_.side_indices("CT")) == 0:
            continue
        filled = fill_missing(round_, zones, RulesConfig(), "infer").round
        options = ReplayOptions(damage_model=model, seed=args.seed, sight=sight)
        result = replay_round(round_, graph, options)
        truth = result.data_deaths
        replay = replay_deaths(result.events, round_.num_players)
        hit_at = {}
        for event in result.events:
            if event.kind == "damage":
                hit_at.setdefault((event.agent, event.other), event.tick / 60)
        rows = {p.name: i for i, p in enumerate(round_.players)}
        steps = sightings(round_, graph, model, sight)
        for kill in round_.kills.itertuples():
            a, v = rows.get(kill.attackerName, -1), rows.get(kill.victimName, -1)
            if a < 0 or v < 0 or kill.weapon not in FIREARMS:
                continue
            kills += 1
            j = int(np.searchsorted(round_.frame_seconds, kill.seconds, side="right") - 1)
            a_pos = np.array([kill.attackerX_m, kill.attackerY_m, round_.position[a, j, 2]])
            v_pos = np.array([kill.victimX_m, kill.victimY_m, round_.position[v, j, 2]])
            if not (np.isfinite(a_pos).all() and np.isfinite(v_pos).all()):
                a_pos, v_pos = round_.position[a, j], round_.position[v, j]
            near = [pairs for at, pairs in steps if -DEATH_WINDOW_S <= at - kill.seconds <= 0.5]
            in_sight["by the real killer"] += any((a, v) in pairs for pairs in near)
            in_sight["by any enemy"] += any(v in {w for _, w in pairs} for pairs in near)
            before_kill = np.flatnonzero(
                (round_.frame_seconds >= kill.seconds - DEATH_WINDOW_S)
                & (round_.frame_seconds <= kill.seconds)
            )
            a_eyes, v_eyes = (eye_point(round_.position[i, before_kill]) for i in (a, v))
            known = np.isfinite(a_eyes).all(axis=1) & np.isfinite(v_eyes).all(axis=1)
            for name, world in worlds.items():
                seen[name] += bool(
                    world.line_of_sight(eye_point(a_pos)[None], eye_point(v_pos)[None])[0]
                )
                seen_frames[name] += bool(world.line_of_sight(a_eyes[known], v_eyes[known]).any())
            before = round_.position[a, max(j - 1, 0)]
            step = round_.position[a, j] - before
            motion = float(facing_yaw(step[0], step[1]))
            aimed = float(facing_yaw(*(v_pos - a_pos)[[0, 1]]))
            weapon = str(filled.weapon[a, j])
            dip["along the motion"] += dip_hits(model, a, v, a_pos, v_pos, motion, weapon)
            dip["aimed at the victim"] += dip_hits(model, a, v, a_pos, v_pos, aimed, weapon)
            t, s = truth.seconds[v], replay.seconds[v]
            fight = bool(replay.by_fight[v]) and np.isfinite(s)
            if fight and abs(s - t) <= DEATH_WINDOW_S:
                fates["killed by the fight within 3 s"] += 1
                continue
            fate = "killed by the fight earlier" if fight and s < t else "not killed by the fight"
            if fight and s > t:
                fate = "killed by the fight later"
            if np.isfinite(replay.seconds[a]) and replay.seconds[a] < t:
                fates[f"{fate}; the real killer was dead in the replay by then"] += 1
            elif (a, v) not in hit_at:
                fates[f"{fate}; the real killer never hit him"] += 1
            else:
                fates[f"{fate}; the real killer hit him first {hit_at[(a, v)] - t:+.0f} s off"] += 1
        for event in result.events:
            if event.kind != "kill" or event.agent is None or event.agent < 0:
                continue
            a, v, at = event.agent, int(event.other), event.tick / TICK_RATE
            right = bool(abs(truth.seconds[v] - at) <= DEATH_WINDOW_S)  # NaN (survived): False
            near = np.flatnonzero(np.abs(round_.frame_seconds - at) <= 1.0)
            a_eyes, v_eyes = (
                eye_point(round_.position[a, near]),
                eye_point(round_.position[v, near]),
            )
            known = np.isfinite(a_eyes).all(axis=1) & np.isfinite(v_eyes).all(axis=1)
            fight_kills[("reproducing a real death" if right else "wrong", "all")] += 1
            for name, world in worlds.items():
                seen_there = bool(world.line_of_sight(a_eyes[known], v_eyes[known]).any())
                fight_kills[("reproducing a real death" if right else "wrong", name)] += seen_there
        hp = np.where(round_.hp >= 0, round_.hp, np.nan).astype(float)
        for player in range(round_.num_players):
            dead = np.flatnonzero(~np.asarray(round_.alive[player], bool))
            if len(dead) and dead[0] > 0:
                hp_before_death.append(hp[player, dead[0] - 1])
        _damage_by_sight(round_, result, worlds["nav world"], by_sight, by_distance)
    print(f"{kills} real firearm kills")
    for name, count in seen.items():
        print(f"  line of sight at the kill, {name}: {count / max(kills, 1):.2f}")
        share = seen_frames[name] / max(kills, 1)
        window = f"{DEATH_WINDOW_S:g} s"
        print(f"  line of sight at a real frame in the {window} before, {name}: {share:.2f}")
    for whom, count in in_sight.items():
        share = count / max(kills, 1)
        where = "in the replay on the real paths (--deaths data)"
        print(f"  victim in sight {whom} {where}: {share:.2f}")
    for name, count in dip.items():
        print(f"  DIP says hit, attacker's yaw {name}: {count / max(kills, 1):.2f}")
    for fate, count in fates.most_common():
        print(f"  {count:3d} {fate}")
    for kind in ("reproducing a real death", "wrong"):
        line = ", ".join(f"{fight_kills[(kind, name)]} in sight in the {name}" for name in worlds)
        print(
            f"  fight's kills {'that are wrong' if kind == 'wrong' else kind}: "
            f"{fight_kills[(kind, 'all')]}; at a real frame within 1 s: {line}"
        )
    frames, real, replay = np.sum(list(by_sight.values()), axis=0)
    print(f"damaged player-frames of {frames} alive in both: data {real}, replay's fight {replay}")
    print("damaged within the next frame, by enemies in sight at the frame (nav world):")
    for seen_by, row in sorted(by_sight.items()):
        count = f"{seen_by}+" if seen_by == SIGHT_BUCKETS - 1 else str(seen_by)
        print(_shares(f"{count} in sight", row))
    print("with an enemy in sight, by the nearest one's distance:")
    edges = (0.0, *DISTANCE_BANDS_M)
    for band, row in sorted(by_distance.items()):
        last = band == len(DISTANCE_BANDS_M)
        label = f"{edges[band]:g}+ m" if last else f"{edges[band]:g}-{DISTANCE_BANDS_M[band]:g} m"
        print(_shares(label, row))
    full = np.asarray(hp_before_death) >= 100
    print(f"real deaths from full HP within one frame: {full.sum()} of {len(full)}")


if __name__ == "__main__":
    main()
