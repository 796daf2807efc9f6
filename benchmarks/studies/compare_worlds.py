"""Line of sight in the built-in nav world vs the moh-maps brush mesh of de_dust2.

Draws random waypoint pairs of the built-in graph within a combat distance (seeded), puts an eye
at standing height over each waypoint, ray-tests every pair in both worlds and reports the
agreement, the confusion table, the agreement by distance and by nav place, and the same without
the pairs whose endpoints do not stand properly in the other world (buried under mesh geometry,
such as the sand mounds, or with no floor within 0.5 m below, such as boxes the mesh lacks).
Writes a top-down plot of the disagreeing pairs and a JSON summary.

    python benchmarks/studies/compare_worlds.py [--pairs 20000] [--seed 0] [--max-distance 40]
        [--plot decoy-out/compare_worlds.png] [--json decoy-out/compare_worlds.json]

Needs ../shared/data/meshes/de_dust2_moh-maps.tri next to the repository (or --mesh); without it
the script says so and exits without comparing.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from collections import Counter
from itertools import pairwise
from pathlib import Path

import numpy as np

from decoy_cli.csgo import PLAYER_RADIUS_M
from decoy_cli.waypoints.build import builtin_graph
from decoy_cli.waypoints.los_pairs import disagreement_by_place, eye_pairs, random_node_pairs
from decoy_cli.world.los import (
    check_placement,
    compare_line_of_sight,
    plot_los_comparison,
    sideways,
)
from decoy_cli.world.meshfile import check_extent, read_mesh
from decoy_cli.world.navmesh import load_navmesh, nav_world
from decoy_cli.world.physics import PhysicsWorld

DATA = Path(__file__).resolve().parents[2].parent / "shared" / "data"
MESH = DATA / "meshes" / "de_dust2_moh-maps.tri"
DISTANCE_BINS = (0.0, 10.0, 20.0, 30.0, 40.0, np.inf)


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--mesh", type=Path, default=MESH, help="the other world (.tri, Hammer)")
    parser.add_argument("--pairs", type=int, default=20_000)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--max-distance", type=float, default=40.0, help="metres")
    parser.add_argument("--plot", type=Path, default=Path("decoy-out") / "compare_worlds.png")
    parser.add_argument("--json", type=Path, default=Path("decoy-out") / "compare_worlds.json")
    args = parser.parse_args()
    if not args.mesh.is_file():
        print(f"skipped: {args.mesh} is absent (the shared data folder is not next to the repo)")
        return 0

    clock = time.perf_counter()
    graph = builtin_graph()
    nav = load_navmesh()
    world_a = nav_world()
    world_b = read_mesh(args.mesh, name="moh-maps")
    check_extent(world_b)
    nodes = random_node_pairs(graph, args.pairs, seed=args.seed, max_distance=args.max_distance)
    eyes = eye_pairs(graph, nodes)
    prepared = time.perf_counter() - clock

    clock = time.perf_counter()
    with PhysicsWorld(world_a) as physics_a, PhysicsWorld(world_b) as physics_b:
        comparison = compare_line_of_sight(physics_a, physics_b, eyes)
        in_a = check_placement(physics_a, graph.positions)
        in_b = check_placement(physics_b, graph.positions)
        compared = time.perf_counter() - clock
        # grazing: moved sideways by a player's half width, the answer in either world changes
        grazing = np.zeros(comparison.num_pairs, dtype=bool)
        for shift in (PLAYER_RADIUS_M, -PLAYER_RADIUS_M):
            moved = sideways(eyes, shift)
            grazing |= physics_a.line_of_sight(moved[:, 0], moved[:, 1]) != comparison.visible_a
            grazing |= physics_b.line_of_sight(moved[:, 0], moved[:, 1]) != comparison.visible_b

    misplaced_b = in_b.misplaced[nodes].any(axis=1)
    misplaced_a = in_a.misplaced[nodes].any(axis=1)
    clean = ~misplaced_a & ~misplaced_b
    distance = np.linalg.norm(eyes[:, 0] - eyes[:, 1], axis=1)

    print(
        f"{comparison.num_pairs:,} pairs of {graph.num_nodes:,} built-in waypoints within "
        f"{args.max_distance:g} m (seed {args.seed}); A = {world_a.name} nav world "
        f"({world_a.num_triangles:,} triangles), B = {world_b.name} ({world_b.num_triangles:,})"
    )
    print(f"prepare {prepared:.2f} s, load both worlds + rays + placement {compared:.2f} s")
    print("\nwaypoints that do not stand properly (of all built-in waypoints):")
    for label, placement in (("in A (nav)", in_a), ("in B (moh)", in_b)):
        print(
            f"  {label}: buried {int(placement.buried.sum()):,}, floating "
            f"{int(placement.floating.sum()):,}, either {int(placement.misplaced.sum()):,}"
        )
    names = np.array([*graph.place_names, "-"])
    misplaced_places = Counter(names[graph.node_place[in_b.misplaced]].tolist()).most_common(8)
    print("  misplaced in B by place: " + ", ".join(f"{p} {n}" for p, n in misplaced_places))
    print(
        f"pairs with a misplaced endpoint: in B {int(misplaced_b.sum()):,}, "
        f"in A {int(misplaced_a.sum()):,}, either {int((~clean).sum()):,}"
    )

    subsets = {"all pairs": comparison, "without misplaced pairs": comparison.subset(clean)}
    print(
        f"\n{'':26} {'pairs':>7} {'agree':>7} {'both':>7} {'only A':>7} {'only B':>7} "
        f"{'neither':>7}"
    )
    for label, part in subsets.items():
        c = part.confusion
        print(
            f"{label:26} {part.num_pairs:7,} {part.agreement:7.2%} {c['both']:7,} "
            f"{c['only_a']:7,} {c['only_b']:7,} {c['neither']:7,}"
        )

    disagree = clean & ~comparison.agree
    print(
        f"\ngrazing (the answer changes in either world when the pair moves "
        f"{PLAYER_RADIUS_M:.2f} m sideways): {int(np.sum(grazing & clean)):,} of "
        f"{int(clean.sum()):,} clean pairs; of the {int(disagree.sum()):,} clean disagreements "
        f"{int(np.sum(grazing & disagree)):,} graze, {int(np.sum(~grazing & disagree)):,} do not; "
        f"agreement on clean non-grazing pairs "
        f"{comparison.subset(clean & ~grazing).agreement:.2%}"
    )
    print("\nby distance (without misplaced pairs):")
    by_distance = []
    for lo, hi in pairwise(DISTANCE_BINS):
        part = comparison.subset(clean & (distance >= lo) & (distance < hi))
        if part.num_pairs:
            row = {"from_m": lo, "to_m": hi, **part.summary()}
            by_distance.append(row)
            print(
                f"  {lo:4.0f}-{hi:<4.0f} m {part.num_pairs:7,} pairs, agree {part.agreement:.2%},"
                f" only A {row['only_a']:,}, only B {row['only_b']:,}"
            )

    places = disagreement_by_place(comparison.subset(clean), nodes[clean], graph)
    print("\nwhere (without misplaced pairs; a pair counts for both endpoint places):")
    print(f"  {'place':16} {'pairs':>6} {'disagree':>9} {'share':>6} {'only A':>7} {'only B':>7}")
    for row in places[:20]:
        print(
            f"  {row.place:16} {row.pairs:6,} {row.disagree:9,} {row.share:6.1%} "
            f"{row.only_a:7,} {row.only_b:7,}"
        )

    plot_los_comparison(
        comparison.subset(clean),
        args.plot,
        nav=nav,
        title=(
            f"line of sight, A = nav world vs B = moh-maps mesh: {int(clean.sum()):,} pairs of "
            f"built-in waypoints within {args.max_distance:g} m with both ends well placed, "
            f"agreement {comparison.subset(clean).agreement:.1%}"
        ),
    )
    print(f"\nplot written to {args.plot}")
    report = {
        "pairs": args.pairs,
        "seed": args.seed,
        "max_distance_m": args.max_distance,
        "world_a": {"name": world_a.name, "triangles": world_a.num_triangles},
        "world_b": {"name": world_b.name, "triangles": world_b.num_triangles},
        "misplaced_nodes": {
            "a": {"buried": int(in_a.buried.sum()), "floating": int(in_a.floating.sum())},
            "b": {"buried": int(in_b.buried.sum()), "floating": int(in_b.floating.sum())},
        },
        "misplaced_pairs": {"a": int(misplaced_a.sum()), "b": int(misplaced_b.sum())},
        **{label.replace(" ", "_"): part.summary() for label, part in subsets.items()},
        "clean_not_grazing": comparison.subset(clean & ~grazing).summary(),
        "clean_disagreements_grazing": int(np.sum(grazing & disagree)),
        "misplaced_nodes_b_by_place": dict(misplaced_places),
        "by_distance_clean": by_distance,
        "by_place_clean": [{**row.__dict__, "share": row.share} for row in places],
        "seconds": {"prepare": prepared, "compare": compared},
    }
    args.json.parent.mkdir(parents=True, exist_ok=True)
    args.json.write_text(json.dumps(report, indent=2) + "\n")
    print(f"JSON written to {args.json}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
