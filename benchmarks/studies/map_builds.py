"""Build every built-in map's waypoint graph and report it:
python benchmarks/studies/map_builds.py [OUT]

For each of the eight ESTA maps: the build time on this machine, nodes, edges by kind, the share
of lattice nodes in the largest strongly connected component before pruning, the waypoints of
each region, the nav mesh's coverage (share of its floor area within 0.5 m of a waypoint) with
its least covered places, and whether each build reproduces the shipped graph byte for byte.
Writes OUT/maps.md (default docs/) and a picture of each graph over its nav mesh to
OUT/maps/<map>.png. Build times are of this machine only (the machine line is printed with them).
"""

from __future__ import annotations

import sys
import tempfile
import time
from pathlib import Path

from decoy_cli.bench.machine import machine_line
from decoy_cli.csgo import MAP_NAMES
from decoy_cli.waypoints.build import GRAPH_FILE, build_graph
from decoy_cli.waypoints.coverage import nav_coverage
from decoy_cli.waypoints.plot import plot_graph
from decoy_cli.world.navmesh import asset_dir, load_navmesh, nav_world

PICTURE_DPI = 50
"""Small pictures: eight of them live in the repository."""


def main() -> None:
    out = Path(sys.argv[1]) if len(sys.argv) > 1 else Path(__file__).parents[2] / "docs"
    (out / "maps").mkdir(parents=True, exist_ok=True)
    machine = machine_line()
    rows = []
    for map_name in MAP_NAMES:
        started = time.perf_counter()
        world = nav_world.__wrapped__(map_name)  # not the cached one: the world build is timed
        graph, result = build_graph(world, map_name)
        seconds = time.perf_counter() - started
        with tempfile.TemporaryDirectory() as folder:
            path = Path(folder) / GRAPH_FILE
            graph.save(path)
            current = path.read_bytes() == (asset_dir(map_name) / GRAPH_FILE).read_bytes()
        nav = load_navmesh(map_name)
        coverage = nav_coverage(graph, nav)
        stats = result.stats
        edges = ", ".join(f"{kind} {count:,}" for kind, count in stats.edges.items())
        regions = ", ".join(f"{name} {len(nodes):,}" for name, nodes in graph.regions.items())
        worst = ", ".join(f"{p or '(unnamed)'} {s:.0%}" for p, s in coverage.worst_places(3))
        picture = out / "maps" / f"{map_name}.png"
        plot_graph(
            graph,
            picture,
            nav=nav,
            title=f"{map_name}: {graph.num_nodes:,} waypoints, {graph.num_edges:,} edges",
            dpi=PICTURE_DPI,
        )
        row = (
            f"| {map_name} | {nav.num_areas:,} | {seconds:.0f} | {graph.num_nodes:,} | {edges} | "
            f"{stats.largest_component_share:.1%} | {regions} | {coverage.covered:.1%} | {worst} "
            f"| {'yes' if current else 'NO'} |"
        )
        print(row, flush=True)
        rows.append(row)
    header = [
        "# The built-in maps",
        "",
        "Made by `python benchmarks/studies/map_builds.py` (build times are of this machine: "
        f"{machine}). Coverage: share of the nav mesh's floor area within 0.5 m of a waypoint "
        "(the graph is its largest strongly connected component); SCC share: lattice nodes in "
        "that component before pruning; ladder edges join the two ends of the map's ladders "
        "(`nav_ladders.csv`), one each way. Pictures: `docs/maps/<map>.png`.",
        "",
        "| map | nav areas | build (s) | nodes | edges | SCC share | region waypoints "
        "| coverage | least covered places | shipped graph reproduced |",
        "|---|---:|---:|---:|---|---:|---|---:|---|---|",
    ]
    (out / "maps.md").write_text("\n".join([*header, *rows]) + "\n")
    print(f"wrote {out / 'maps.md'} and {len(rows)} pictures in {out / 'maps'}")


if __name__ == "__main__":
    main()
