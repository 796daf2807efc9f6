"""The real data behind the reader's and the replay's plausibility limits (README, "What the
reader and the replay refuse").

    python benchmarks/studies/plausibility_study.py ../shared/data/esta_dust2_tside

Prints, over every round of the folder: the largest JSON of a file after decompression, the most
rounds in a file, frames and distinct players in a round and player-frames in a file, the median
time between frames, the latest frame time, the fastest movement of an alive player between two
frames, the largest HP and armor, alive flags that contradict HP, the most players of a side in
one frame, and how far an alive player stood outside the built-in graph's bounding box; the
impossible histories (players alive again after being dead, HP rising, a player on both sides,
rounds that start before the round before them ended); next to the limits in force.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

from decoy_cli.esta import RoundFailure, collect_match_files, iter_rounds
from decoy_cli.esta.frames import MAX_FRAMES, MAX_PLAYERS, MAX_ROUND_S
from decoy_cli.esta.plausibility import MAX_ARMOR, MAX_HP, MAX_PER_SIDE, MAX_SPEED_M_S
from decoy_cli.esta.reader import MAX_MATCH_PLAYER_FRAMES
from decoy_cli.esta.source import MAX_ROUNDS, max_match_bytes, read_bytes
from decoy_cli.replay.replayer import OFF_MAP_M
from decoy_cli.waypoints.build import builtin_graph


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("folder", type=Path)
    args = parser.parse_args()
    files, _ = collect_match_files([args.folder])
    graph = builtin_graph()
    low, high = graph.positions.min(axis=0), graph.positions.max(axis=0)
    json_mb = max(len(read_bytes(file)) for file in files) / 1e6
    last_s = speed = outside = 0.0
    hp = armor = contradictions = per_side = rounds = failures = 0
    revived = rising = both_sides = backwards = pairs = 0
    last_end: dict[str, tuple[int, int | None]] = {}  # file -> (round, end tick) read last
    players = frames = 0
    steps: list[float] = []
    player_frames: dict[str, int] = {}
    rounds_in: dict[str, int] = {}  # file -> its rounds, built or failed
    for item in iter_rounds(files):
        source = str(item.file if isinstance(item, RoundFailure) else item.path)
        rounds_in[source] = rounds_in.get(source, 0) + 1
        if isinstance(item, RoundFailure):
            failures += 1
            continue
        before = last_end.get(source)
        if before is not None and before[1] is not None and item.start_tick is not None:
            pairs += 1  # iter_rounds yields a file's rounds by number
            backwards += int(item.start_tick < before[1])
        last_end[source] = (item.round_num, item.end_tick)
        if item.num_frames == 0:
            continue
        rounds += 1
        last_s = max(last_s, float(item.frame_seconds[-1]))
        players, frames = max(players, item.num_players), max(frames, item.num_frames)
        player_frames[source] = player_frames.get(source, 0) + item.num_players * item.num_frames
        if item.num_frames > 1:
            steps.append(float(np.median(np.diff(item.frame_seconds))))
        usable = item.present & item.alive & np.isfinite(item.position).all(axis=2)
        step = np.linalg.norm(np.diff(item.position, axis=1), axis=2)
        dt = np.diff(item.frame_seconds)
        both = usable[:, 1:] & usable[:, :-1] & (dt > 0)[None, :]
        if both.any():
            speed = max(speed, float((step / np.where(dt > 0, dt, 1.0))[both].max()))
        hp, armor = max(hp, int(item.hp.max())), max(armor, int(item.armor.max()))
        known = item.present & (item.hp >= 0)
        contradictions += int((known & (item.alive != (item.hp > 0))).sum())
        dead = item.present & ~item.alive
        revived += int((item.present & item.alive & np.logical_or.accumulate(dead, axis=1)).sum())
        for p in range(item.num_players):
            known_hp = item.hp[p][item.present[p] & (item.hp[p] >= 0)].astype(int)
            rising += int((np.diff(known_hp) > 0).sum())
        keys = [player.key for player in item.players]
        both_sides += len(keys) - len(set(keys))
        for side in ("T", "CT"):
            side_rows = item.side_indices(side)
            if len(side_rows):
                per_side = max(per_side, int(item.present[side_rows].sum(axis=0).max()))
        points = item.position[usable]
        if len(points):
            outside = max(outside, float(np.maximum(low - points, points - high).max()))
    print(f"{len(files)} files, {rounds} rounds with frames, {failures} failures")
    rows = [
        ("largest JSON of a file (MB)", f"{json_mb:.1f}", f"{max_match_bytes() / 1e6:g}"),
        ("rounds in a file", str(max(rounds_in.values())), str(MAX_ROUNDS)),
        ("latest frame time (s)", f"{last_s:.1f}", f"{MAX_ROUND_S:g}"),
        ("frames in a round", str(frames), str(MAX_FRAMES)),
        ("median time between frames (s)", f"{np.median(steps):.2f}" if steps else "–", "–"),
        ("distinct players in a round", str(players), str(MAX_PLAYERS)),
        (
            "player-frames in a file",
            str(max(player_frames.values(), default=0)),
            str(MAX_MATCH_PLAYER_FRAMES),
        ),
        ("fastest alive movement between frames (m/s)", f"{speed:.1f}", f"{MAX_SPEED_M_S:.1f}"),
        ("largest HP / armor", f"{hp} / {armor}", f"{MAX_HP} / {MAX_ARMOR}"),
        ("alive flags contradicting HP", str(contradictions), "0"),
        ("most players of a side in a frame", str(per_side), str(MAX_PER_SIDE)),
        ("player-frames alive after being dead", str(revived), "0"),
        ("HP rises between a player's frames", str(rising), "0"),
        ("players on both sides of a round", str(both_sides), "0"),
        (f"rounds starting before the previous ended ({pairs} pairs)", str(backwards), "0"),
        ("farthest alive position outside the graph's box (m)", f"{outside:.2f}", f"{OFF_MAP_M:g}"),
    ]
    print(f"{'measure':<54}{'data':>12}{'limit':>12}")
    for name, value, limit in rows:
        print(f"{name:<54}{value:>12}{limit:>12}")


if __name__ == "__main__":
    main()
