"""Simulator speed, as in the DECOY paper's Table 1: physics ticks per second by agent count.

    python benchmarks/bench/bench_sim.py [--mover physics] [--decisions 10000]
        [--agents 2 6 10 20 100] [--models FOLDER] [--json out.json]

The measurement is `decoy_cli.bench.simspeed` (see its docstring), the same code as the Table 1
section of `decoy bench`; this script runs it alone, with any agent counts and decision count.
Without `--models` the combat step runs line of sight with a model that never hits (no
inference cost); with a model folder (e.g. from `decoy models import-decoy`) it runs DIP + DOG.
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

from decoy_cli.bench.machine import machine_info
from decoy_cli.bench.simspeed import AGENT_COUNTS, PAPER_DECISIONS, speed_table
from decoy_cli.damage import load_damage_model
from decoy_cli.sim.setup import MOVERS


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--mover", default="physics", choices=MOVERS)
    parser.add_argument("--decisions", type=int, default=PAPER_DECISIONS)
    parser.add_argument("--agents", type=int, nargs="*", default=list(AGENT_COUNTS))
    parser.add_argument("--models", default="none", help='"none", "shipped" or a model folder')
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--json", type=Path, default=None)
    args = parser.parse_args()
    machine = machine_info()
    print(f"machine: {machine['cores']} cores, {machine['cpu']}, load {machine['load_average']}")
    model = load_damage_model(args.models)
    print(f"damage model: {args.models if model else 'none (line of sight only)'}")
    rows = speed_table(tuple(args.agents), args.decisions, model, mover=args.mover, seed=args.seed)
    print(
        "agents  ticks  decisions  wall s  game s  ticks/s  time scale  paper's table (its machine)"
    )
    for row in rows:
        paper = row.paper_ticks_per_s
        print(
            f"{row.agents:>6} {row.ticks:>6} {row.decisions:>10} {row.wall_s:>7.2f} "
            f"{row.game_s:>7.1f} {row.ticks_per_s:>8.0f} {row.time_scale:>11.1f} "
            f"{paper if paper else '-':>14}"
        )
    if args.json:
        args.json.parent.mkdir(parents=True, exist_ok=True)
        args.json.write_text(json.dumps([row.to_dict() for row in rows], indent=2) + "\n")


if __name__ == "__main__":
    main()
