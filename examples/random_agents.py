"""Random agents on de_dust2: every agent picks a uniformly random allowed action whenever it
needs a decision, for a few rounds; prints how each round ended and what it cost.

    python examples/random_agents.py --rounds 3 --seed 0 --mover kinematic --models rules

Combat: `--models rules` (the default, as on every decoy command) shoots with the DIP shipped with
decoy and damage by the game's rules, `--models shipped` with that DIP and the shipped DOG
(`models/`, trained by the project; see their cards), `--models none` turns shooting off (nobody
dies), and `--models FOLDER` uses another model folder (e.g. from `decoy models import-decoy`). In
code the environment takes the model, or a function that loads it:
`DecoyParallelEnv(damage_model=lambda: load_damage_model("rules"))`; its own default is no
combat.

Random walkers stay near their spawns (in the seed-0 round the two sides never come closer than
about 50 m): they rarely reach a bomb site, let alone STOP there for the whole plant, and rarely
meet, so even with combat on most rounds end "TargetSaved" at 115 s.
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from decoy_cli.damage import CHOICES_HELP, DEFAULT_MODELS, load_damage_model
from decoy_cli.env import DecoyParallelEnv


def main() -> None:
    parser = argparse.ArgumentParser(
        description="Random masked agents on de_dust2 for a few rounds: outcome and cost per round."
    )
    parser.add_argument("--rounds", type=int, default=3, help="rounds to play (default 3)")
    parser.add_argument("--seed", type=int, default=0, help="seed of spawns and actions")
    parser.add_argument(
        "--mover",
        choices=("kinematic", "physics"),
        default="kinematic",
        help="kinematic (no collisions) or physics (pybullet capsules that block each other)",
    )
    parser.add_argument("--models", default=DEFAULT_MODELS, help=f"damage models: {CHOICES_HELP}")
    args = parser.parse_args()
    if args.rounds < 1:
        parser.error("--rounds must be at least 1")

    env = DecoyParallelEnv(mover=args.mover, damage_model=lambda: load_damage_model(args.models))
    rng = np.random.default_rng(args.seed)
    print(f"{'round':>5} {'winner':>6} {'reason':<14} {'ticks':>6} {'decisions':>9} {'wall s':>7}")
    try:
        for number in range(1, args.rounds + 1):
            start = time.perf_counter()
            obs, infos = env.reset(seed=args.seed if number == 1 else None)
            while env.agents:
                actions = {
                    agent: int(rng.choice(np.flatnonzero(obs[agent]["action_mask"])))
                    for agent in env.agents
                }
                obs, _, _, _, infos = env.step(actions)
            wall = time.perf_counter() - start
            end = next(iter(infos.values()))
            sim = env.sim
            print(
                f"{number:>5} {end['winner']:>6} {end['reason']:<14} {sim.tick:>6} "
                f"{int(sim.state.decisions.sum()):>9} {wall:>7.2f}"
            )
    finally:
        env.close()


if __name__ == "__main__":
    main()
