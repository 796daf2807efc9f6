"""How closely every kind of edge replays on every map: synthetic rounds that take one step,
jump, drop (without fall damage) or ladder edge each, moving as a CS:GO player does
(`decoy_cli.synth.edge_rounds`), replayed with movement only.

    python benchmarks/studies/edge_kinds.py [--rate 2] [--per-kind 3] [--seed 0] [--maps dust2,nuke]

Prints per map and kind: the graph's edges of that kind, the rounds replayed, their clock
`mean_dist` (mean and largest) and `max_dist` (largest), and how many replay within 0.5 m
(`mean_dist`). The runner runs at 90% of the knife's speed. Nothing here is timed.
"""

from __future__ import annotations

import argparse
import tempfile
from pathlib import Path

import numpy as np

from decoy_cli.csgo import MAP_NAMES
from decoy_cli.esta import read_match
from decoy_cli.esta.writer import write_match
from decoy_cli.metrics import player_metrics
from decoy_cli.replay import ReplayOptions, replay_round
from decoy_cli.synth.edge_rounds import KINDS, edge_match
from decoy_cli.waypoints.build import builtin_graph, canonical_map
from decoy_cli.weapons import max_speed_m_s

WITHIN_M = 0.5


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rate", type=float, default=2.0, help="frames per second")
    parser.add_argument("--per-kind", type=int, default=3)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--maps", default=",".join(MAP_NAMES))
    args = parser.parse_args()
    speed = 0.9 * max_speed_m_s("Knife")
    print(f"{args.rate:g} frames/s, runner at {speed:.2f} m/s, seed {args.seed}")
    heads = f"{'edges':>7}{'rounds':>7}{'mean':>7}{'worst':>7}{'max':>7}"
    print(f"{'map':<12}{'kind':<8}{heads}  within")
    with tempfile.TemporaryDirectory() as scratch:
        for map_name in (canonical_map(m) for m in args.maps.split(",")):
            graph = builtin_graph(map_name)
            record, kinds = edge_match(graph, args.per_kind, args.seed, speed, args.rate)
            path = write_match(record, Path(scratch) / f"{map_name}.json.xz")
            rows = []
            for round_, kind in zip(read_match(path).rounds, kinds, strict=True):
                replay = replay_round(round_, graph, ReplayOptions(combat=False, bomb=False))
                row = player_metrics(round_, replay.trace()).iloc[0]
                rows.append((kind, row["mean_dist"], row["max_dist"]))
            for kind in KINDS:
                mean = np.array([m for k, m, _ in rows if k == kind])
                worst = np.array([x for k, _, x in rows if k == kind])
                edges = int(np.count_nonzero(graph.edge_kind == kind))
                if not len(mean):
                    print(f"{map_name:<12}{kind.name.lower():<8}{edges:>7}{0:>7}")
                    continue
                within = int(np.count_nonzero(mean <= WITHIN_M))
                figures = f"{mean.mean():>7.2f}{mean.max():>7.2f}{worst.max():>7.2f}"
                name = f"{map_name:<12}{kind.name.lower():<8}{edges:>7}{len(mean):>7}"
                print(f"{name}{figures}  {within}/{len(mean)}")


if __name__ == "__main__":
    main()
