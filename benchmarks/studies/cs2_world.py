"""CS2's de_dust2 world (from its nav mesh) against the built-in CS:GO one, side by side.

Builds the CS2 world and its graph from ../shared/data/cs2_maps/de_dust2.nav.json.xz (or loads
the graph given with --graph), then measures on both:

* the map check: the share of the CS2 nav's areas on each built-in map's nav;
* walls: how far beyond the CS2 nav's open edges the brush mesh's walls stand (the measurement
  behind `POLYGON_WALL_PUSH_U`), rays at 20 and 64 u above the floor;
* line of sight against the brush mesh (../shared/data/meshes): random pairs of each world's
  own waypoints within 40 m, the same pairs of the built-in graph's waypoints in both worlds,
  and the real kills of the 12 CS2 rounds (killer's and victim's eyes at the kill's frame);
* movement on the 12 real CS2 rounds (`decoy evaluate --no-combat --no-bomb`): by side, median
  `mean_dist`, p90 `max_dist`, relocations, targets more than a frame late; and the snapping
  floor (`decoy snap`'s measures);
* with --seeds N: the whole round over seeds 0..N-1 under both death protocols (winner
  agreement and plants, medians over the seeds).

    python benchmarks/studies/cs2_world.py [--graph G.npz] [--seeds 20] [--out decoy-out/cs2_world]

Without ../shared/data it says so and exits.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pandas as pd

from decoy_cli.csgo import HAMMER_TO_M, MAP_NAMES
from decoy_cli.esta import read_match
from decoy_cli.geometry import eye_point
from decoy_cli.waypoints.build import build_graph, builtin_graph, graph_world
from decoy_cli.waypoints.graph import WaypointGraph
from decoy_cli.waypoints.los_pairs import eye_pairs, random_node_pairs
from decoy_cli.world.cs2_world import cs2_world, on_map_share
from decoy_cli.world.los import compare_line_of_sight
from decoy_cli.world.meshfile import read_mesh
from decoy_cli.world.nav_json import read_nav
from decoy_cli.world.nav_polygons import open_edge_rays
from decoy_cli.world.navmesh import nav_world
from decoy_cli.world.physics import PhysicsWorld

DATA = Path(__file__).resolve().parents[2].parent / "shared" / "data"
NAV = DATA / "cs2_maps" / "de_dust2.nav.json.xz"
MESH = DATA / "meshes" / "de_dust2_moh-maps.tri"
ROUNDS = DATA / "cs2_dust2_both" / "spirit-vs-falcons-m2-dust2-r01-12.json.xz"


def wall_distances(physics_brush: PhysicsWorld) -> np.ndarray:
    """Distances (Hammer units) from the CS2 nav's open edges with no floor beyond to the
    brush mesh's walls, for the rays that hit one within 200 u."""
    starts, ends, back = open_edge_rays(read_nav(NAV), heights=(20.0, 64.0), reach=200.0)
    fraction, _ = physics_brush.ray_test(starts * HAMMER_TO_M, ends * HAMMER_TO_M)
    hit = np.isfinite(fraction) & (fraction < 1)
    return fraction[hit] * (200.0 + back) - back


def kill_eyes() -> np.ndarray:
    """(K, 2, 3) metres: killer's and victim's eyes at the frame of each real kill."""
    eyes = []
    for round_ in read_match(ROUNDS).rounds:
        names = [p.name for p in round_.players]
        for kill in round_.kills.itertuples():
            if kill.attackerName not in names or kill.victimName not in names:
                continue
            frame = int(kill.frame_index)
            a, v = names.index(kill.attackerName), names.index(kill.victimName)
            pair = [round_.position[a, frame], round_.position[v, frame]]
            if np.all(np.isfinite(pair)):
                eyes.append(eye_point(np.array(pair)))
    return np.asarray(eyes)


def movement(graph_file: Path | None, out: Path) -> dict[str, object]:
    """Movement figures of the 12 rounds replayed on a graph (None: the built-in one)."""
    extra = ["--graph", str(graph_file)] if graph_file else []
    command = ["decoy", "evaluate", str(ROUNDS), "--no-combat", "--no-bomb", "--no-figures"]
    subprocess.run(
        [*command, "--out", str(out), *extra],
        check=True,
        capture_output=True,
    )
    players = pd.read_csv(out / "players.csv")
    row: dict[str, object] = {}
    for side in ("CT", "T"):
        part = players[players.side == side]
        row[f"{side} mean_dist median"] = round(float(part.mean_dist.median()), 3)
        row[f"{side} max_dist p90"] = round(float(part.max_dist.quantile(0.9)), 2)
        row[f"{side} relocations"] = int(part.relocations.sum())
    row["targets > 0.5 s late"] = f"{int(players.late_over_frame.sum())} of {players.targets.sum()}"
    return row


def snapping(graph_file: Path | None) -> dict[str, str]:
    """`decoy snap`'s summary measures of the 12 rounds on a graph."""
    extra = ["--graph", str(graph_file)] if graph_file else []
    text = subprocess.run(
        ["decoy", "snap", str(ROUNDS), *extra],
        check=True,
        capture_output=True,
        text=True,
        env={**os.environ, "COLUMNS": "200", "PATH": sys.exec_prefix + "/bin:/usr/bin:/bin"},
    ).stdout
    keep = ("snap error median", "snapped within 0.5 m", "unsnappable", "in the air", "unreachable")
    found = {}
    for line in text.splitlines():
        cells = [c.strip() for c in line.strip("│┃ ").split("│")]
        if len(cells) == 2 and any(cells[0].startswith(k) for k in keep):
            found[cells[0]] = cells[1]
    return found


def whole_rounds(graph_file: Path | None, seeds: int, out: Path) -> dict[str, object]:
    """Winner agreement, plants, the real deaths the replay reproduces and the killers it
    gets right, over seeds, under both death protocols (medians)."""
    extra = ["--graph", str(graph_file)] if graph_file else []
    result: dict[str, object] = {}
    for deaths in ("data", "simulated"):
        winners, plants, recalled, killers = [], [], [], []
        for seed in range(seeds):
            folder = out / f"{deaths}-{seed}"
            subprocess.run(
                ["decoy", "evaluate", str(ROUNDS), "--seed", str(seed), "--deaths", deaths,
                 "--no-figures", "--out", str(folder), *extra],
                check=True,
                capture_output=True,
            )  # fmt: skip
            rounds = pd.read_csv(folder / "rounds.csv")
            winners.append(float((rounds.winner_original == rounds.winner_replay).mean()))
            plants.append(int(rounds.plant_replay.fillna(False).astype(bool).sum()))
            recalled.append(rounds.deaths_recalled.sum() / rounds.deaths_original.sum())
            killers.append(rounds.killers_agree.sum() / max(1, rounds.killers_known.sum()))
        result[f"winner agreement ({deaths})"] = round(float(np.median(winners)), 3)
        result[f"plants ({deaths})"] = float(np.median(plants))
        result[f"real deaths reproduced ({deaths})"] = round(float(np.median(recalled)), 3)
        result[f"killer agrees ({deaths})"] = round(float(np.median(killers)), 3)
    return result


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--graph", type=Path, help="a graph built with --nav (default: build)")
    parser.add_argument("--seeds", type=int, default=0, help="seeds of the whole-round runs")
    parser.add_argument("--pairs", type=int, default=20_000)
    parser.add_argument("--out", type=Path, default=Path("decoy-out") / "cs2_world")
    args = parser.parse_args()
    if not all(p.is_file() for p in (NAV, MESH, ROUNDS)):
        print(f"skipped: {DATA} lacks the CS2 nav, the brush mesh or the CS2 rounds")
        return 0
    args.out.mkdir(parents=True, exist_ok=True)
    graph_file = args.graph or args.out / "de_dust2.cs2.npz"
    if args.graph is None:
        graph, _ = build_graph(cs2_world(NAV, "de_dust2"), "de_dust2")
        graph.save(graph_file)
    graphs = {"CS:GO nav world": builtin_graph(), "CS2 nav world": WaypointGraph.load(graph_file)}
    worlds = {name: graph_world(g) for name, g in graphs.items()}
    worlds["CS:GO nav world"] = nav_world()
    report: dict[str, dict[str, object]] = {name: {} for name in graphs}
    brush = read_mesh(MESH, name="moh-maps")
    shared = eye_pairs(
        graphs["CS:GO nav world"],
        random_node_pairs(graphs["CS:GO nav world"], args.pairs, seed=0, max_distance=40.0),
    )
    kills = kill_eyes()
    nav = read_nav(NAV)
    shares = {name: round(on_map_share(nav, name), 3) for name in MAP_NAMES}
    print(f"CS2 de_dust2 nav's area centres within 1 m of each built-in nav: {shares}")
    with PhysicsWorld(brush) as physics_brush:
        distances = wall_distances(physics_brush)
        print(
            f"CS2 nav open edge to brush wall: {len(distances):,} rays, percentiles 10/25/50/75/90 "
            f"{np.percentile(distances, [10, 25, 50, 75, 90]).round(1).tolist()} u"
        )
        for name, graph in graphs.items():
            own = eye_pairs(graph, random_node_pairs(graph, args.pairs, seed=0, max_distance=40.0))
            with PhysicsWorld(worlds[name]) as physics:
                for label, pairs in (("own", own), ("built-in", shared), ("real kills", kills)):
                    agree = compare_line_of_sight(physics, physics_brush, pairs).agreement
                    report[name][f"sight agreement, {label} pairs"] = round(agree, 4)
    report["CS:GO nav world"]["real kills"] = len(kills)
    for name, graph_path in (("CS:GO nav world", None), ("CS2 nav world", graph_file)):
        slug = "csgo" if graph_path is None else "cs2"
        report[name].update(movement(graph_path, args.out / f"movement-{slug}"))
        report[name].update(snapping(graph_path))
        if args.seeds:
            report[name].update(whole_rounds(graph_path, args.seeds, args.out / f"rounds-{slug}"))
    table = pd.DataFrame(report)
    print(table.to_string())
    (args.out / "cs2_world.json").write_text(json.dumps(report, indent=2) + "\n")
    print(f"JSON written to {args.out / 'cs2_world.json'}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
