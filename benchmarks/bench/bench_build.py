"""Time building the built-in de_dust2 waypoint graph (what `decoy build-waypoints` does).

Each run rebuilds the nav world from the nav mesh (its per-process cache cleared), builds the
graph from the default spawn seeds and saves it; it reports the median and range over the runs
of the total and of each stage, the graph's node and edge counts, the share of lattice nodes in
the largest strongly connected component, and whether the file equals the shipped one.

    python benchmarks/bench/bench_build.py [--runs 3] [--json build.json]
"""

from __future__ import annotations

import argparse
import importlib.metadata
import json
import os
import platform
import tempfile
import time
from pathlib import Path

import numpy as np

from decoy_cli.waypoints.build import GRAPH_FILE, build_graph
from decoy_cli.world.navmesh import asset_dir, load_navmesh, nav_world

STAGES = ("nav world", "lattice", "drop pass", "verification", "pruning", "load+places", "save")


def one_run(folder: Path) -> tuple[dict[str, float], dict, bool]:
    """Build once; (seconds per stage and in total, build stats, file equals the shipped one)."""
    seconds: dict[str, float] = {}
    start = time.perf_counter()
    nav_world.cache_clear()
    world = nav_world()
    seconds["nav world"] = time.perf_counter() - start

    clock = time.perf_counter()
    graph, result = build_graph(world)
    total_build = time.perf_counter() - clock
    seconds.update(result.stats.seconds)
    # what build_graph does besides the lattice stages: pybullet load, places and regions
    seconds["load+places"] = total_build - sum(result.stats.seconds.values())

    clock = time.perf_counter()
    out = folder / GRAPH_FILE
    graph.save(out)
    seconds["save"] = time.perf_counter() - clock
    seconds["total"] = time.perf_counter() - start
    same = out.read_bytes() == (asset_dir() / GRAPH_FILE).read_bytes()
    return seconds, result.stats.as_dict(), same


def summary(values: list[float]) -> dict[str, float]:
    return {"median": float(np.median(values)), "min": min(values), "max": max(values)}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=3)
    parser.add_argument("--json", type=Path, help="also write the results as JSON here")
    args = parser.parse_args()

    load_navmesh()  # reading the CSV assets is not part of a build
    runs, stats, matches = [], {}, []
    with tempfile.TemporaryDirectory() as folder:
        for k in range(args.runs):
            seconds, stats, same = one_run(Path(folder))
            runs.append(seconds)
            matches.append(same)
            print(f"run {k + 1}/{args.runs}: {seconds['total']:.2f} s", flush=True)

    timing = {name: summary([r[name] for r in runs]) for name in (*STAGES, "total")}
    edges = stats["edges"]
    report = {
        "benchmark": "build the built-in de_dust2 waypoint graph",
        "runs": args.runs,
        "machine": {
            "cpus": os.cpu_count(),
            "python": platform.python_version(),
            "numpy": np.__version__,
            "pybullet": importlib.metadata.version("pybullet"),
            "platform": platform.platform(),
        },
        "seconds": timing,
        "seconds_per_run": runs,
        "nodes": stats["nodes"],
        "edges": sum(edges.values()),
        "edges_by_kind": edges,
        "lattice_nodes": stats["lattice_nodes"],
        "largest_scc_share": stats["largest_component_share"],
        "components_before_pruning": stats["components_before"],
        "nudged_nodes": stats["nudged_nodes"],
        "matches_shipped_graph": all(matches),
    }

    print()
    print(f"{'stage':<14}{'median s':>10}{'min s':>9}{'max s':>9}")
    for name, t in timing.items():
        print(f"{name:<14}{t['median']:>10.2f}{t['min']:>9.2f}{t['max']:>9.2f}")
    print()
    print(f"nodes {report['nodes']:,}, edges {report['edges']:,} ", end="")
    print("(" + ", ".join(f"{k} {v:,}" for k, v in edges.items()) + ")")
    print(
        f"largest SCC held {report['largest_scc_share']:.2%} of {report['lattice_nodes']:,} "
        f"lattice nodes ({report['components_before_pruning']} components before pruning)"
    )
    print(f"identical to the shipped graph: {'yes' if report['matches_shipped_graph'] else 'NO'}")
    if args.json:
        args.json.parent.mkdir(parents=True, exist_ok=True)
        args.json.write_text(json.dumps(report, indent=2) + "\n")
        print(f"JSON written to {args.json}")


if __name__ == "__main__":
    main()
