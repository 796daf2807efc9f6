"""Cost of the learned damage models per combat step: DIP + DOG inference alone, and the full
step with line of sight, for 5v5 and 50v50, with `LearnedDamage` on one torch thread (its
default) and on torch's default thread count (`threads=None`).

Run: python benchmarks/bench/bench_damage.py [--models FOLDER] [--repeats N] [--seed S]

Models: a model folder (--models), else the paper's checkpoints imported from
../shared/data/decoy_checkpoints when present (its DIP fires often: the DOG share is realistic),
else random networks of the same architecture. Agents stand at random waypoints of the built-in
graph, new positions every step, half T (AK-47) and half CT (M4A4), in two layouts as in
decoy_cli/bench/combat.py: spread over the map and clustered within 15 m (many visible pairs).

Parts, milliseconds per step, median and range over the steps:
* `inference visible`: `LearnedDamage` on the batch of the pairs that see each other (feature
  encoding, one DIP pass, one DOG pass on the pairs DIP selects, damage);
* `inference all pairs`: the same on every ordered enemy pair (everyone sees everyone: the
  largest batch a step can have, 50 pairs at 5v5 and 5,000 at 50v50);
* `full step`: `CombatStep.run` (line of sight, batch, model, damage applied).
"""

from __future__ import annotations

import argparse
import copy
import importlib.metadata
import os
import platform
import statistics
import tempfile
import time
from pathlib import Path

import numpy as np
import torch

from decoy_cli.bench.combat import random_agents
from decoy_cli.damage.combat import LearnedDamage
from decoy_cli.damage.features import FeatureSpec
from decoy_cli.damage.model_folder import (
    LoadedDip,
    LoadedDog,
    load_dip,
    load_dog,
    save_dip,
    save_dog,
)
from decoy_cli.damage.networks import DipNet, DogNet
from decoy_cli.modeling.paper_import import import_paper
from decoy_cli.sim.combat import CombatStep, LineOfSight, VisiblePairs, make_batch
from decoy_cli.waypoints.build import builtin_graph
from decoy_cli.world.navmesh import nav_world
from decoy_cli.world.physics import PhysicsWorld

CHECKPOINTS = Path(__file__).resolve().parents[2].parent / "shared" / "data" / "decoy_checkpoints"


def load_models(folder: Path | None, scratch: Path) -> tuple[LoadedDip, LoadedDog, str]:
    """The models to time and a line saying which they are."""
    if folder is None and (CHECKPOINTS / "dip_best_model.pth").is_file():
        folder = import_paper(CHECKPOINTS, scratch / "paper").folder
        label = f"the paper's checkpoints ({CHECKPOINTS})"
    elif folder is None:
        torch.manual_seed(0)
        folder = scratch / "random"
        save_dip(folder, DipNet(), FeatureSpec(), 0.5)
        save_dog(folder, DogNet(), FeatureSpec())
        label = "random networks (no checkpoints found)"
    else:
        label = str(folder)
    return load_dip(folder), load_dog(folder), label


def all_pairs(per_side: int) -> VisiblePairs:
    """Every ordered (attacker, victim) pair of opposite sides, T = 0..per_side-1."""
    t, ct = np.meshgrid(np.arange(per_side), np.arange(per_side, 2 * per_side), indexing="ij")
    attacker = np.concatenate([t.ravel(), ct.ravel()])
    victim = np.concatenate([ct.ravel(), t.ravel()])
    return VisiblePairs(attacker.astype(np.int64), victim.astype(np.int64))


def time_case(
    model: LearnedDamage,
    step: CombatStep,
    per_side: int,
    clustered: bool,
    repeats: int,
    rng: np.random.Generator,
) -> tuple[dict[str, list[float]], dict[str, list[int]]]:
    """Seconds per part over `repeats` steps, and the batch and DOG sizes of each step."""
    graph = builtin_graph()
    times: dict[str, list[float]] = {"inference visible": [], "inference all pairs": []}
    times["full step"] = []
    sizes: dict[str, list[int]] = {"visible": [], "dog visible": [], "dog all": []}
    everyone = all_pairs(per_side)
    for _ in range(repeats):
        agents = random_agents(graph, per_side, clustered, rng)
        stepped = copy.deepcopy(agents)
        t0 = time.perf_counter()
        step.run(stepped, 30, rng)  # every capsule moves: new positions
        t1 = time.perf_counter()
        pairs = step.los.visible_pairs(agents)
        visible = make_batch(agents, pairs, "de_dust2")
        batch = make_batch(agents, everyone, "de_dust2")
        t2 = time.perf_counter()
        result = model(visible, rng)
        t3 = time.perf_counter()
        full = model(batch, rng)
        t4 = time.perf_counter()
        times["full step"].append(t1 - t0)
        times["inference visible"].append(t3 - t2)
        times["inference all pairs"].append(t4 - t3)
        sizes["visible"].append(len(pairs))
        sizes["dog visible"].append(int(result.hit.sum()))
        sizes["dog all"].append(int(full.hit.sum()))
    return times, sizes


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--models", type=Path, default=None, help="model folder to time")
    parser.add_argument("--repeats", type=int, default=300, help="timed steps per 5v5 case")
    parser.add_argument("--seed", type=int, default=0, help="seed of the agent placements")
    args = parser.parse_args()
    default_threads = torch.get_num_threads()
    world = nav_world()
    with tempfile.TemporaryDirectory() as scratch:
        dip, dog, label = load_models(args.models, Path(scratch))
    print(
        f"python {platform.python_version()}, torch {torch.__version__}, numpy {np.__version__}, "
        f"pybullet {importlib.metadata.version('pybullet')}, {os.cpu_count()} CPUs; "
        f"models: {label}"
    )
    print(
        f"{'case':<18} {'threads':>7} {'part':<20} {'steps':>6} {'median ms':>10} {'min ms':>8} "
        f"{'max ms':>8}  sizes (mean)"
    )
    with PhysicsWorld(world) as physics:
        for per_side, repeats in ((5, args.repeats), (50, max(args.repeats // 10, 5))):
            los = LineOfSight(physics, 2 * per_side)
            for clustered in (False, True):
                for threads in (1, None):
                    model = LearnedDamage(dip, dog, threads=threads)
                    step = CombatStep(los, model, "de_dust2")
                    rng = np.random.default_rng(args.seed)
                    time_case(model, step, per_side, clustered, 3, rng)  # warm-up
                    times, sizes = time_case(model, step, per_side, clustered, repeats, rng)
                    case = f"{per_side}v{per_side} {'clustered' if clustered else 'spread'}"
                    note = (
                        f"visible pairs {statistics.mean(sizes['visible']):.1f}, DOG rows "
                        f"{statistics.mean(sizes['dog visible']):.1f} (all pairs: "
                        f"{statistics.mean(sizes['dog all']):.0f})"
                    )
                    for part, seconds in times.items():
                        ms = np.array(seconds) * 1e3
                        print(
                            f"{case:<18} {threads or default_threads:>7} {part:<20} {len(ms):>6} "
                            f"{np.median(ms):>10.3f} {ms.min():>8.3f} {ms.max():>8.3f}  "
                            f"{note if part == 'full step' else ''}"
                        )
            los.close()


if __name__ == "__main__":
    main()
