"""Where a PettingZoo environment step's time goes:
python benchmarks/profile/env_step_profile.py [ROUNDS]

Plays `decoy bench`'s environment section (5v5, kinematic mover, the shipped models, each agent
that needs a decision taking a random allowed action) for ROUNDS rounds after a warm-up round,
with the environment's parts timed by wrapping them: the whole PettingZoo `step`, the game's
step under it (`DecoyArrayEnv.step`), and in that the compiled quiet stretches
(`env_step._quiet_step`), the ticks played whole in Python (`Simulator.step`; of them the
combat steps), the state after steps that ended in Python (`RoundSteps._finish`, less the
round's first state, which `reset` asks for) and the quiet steps' shared state
(`RoundSteps._quiet_from_here`); then the observation and info dictionaries. What a step spends
outside its parts is its own Python, and what the round costs outside `step` is the
benchmark's loop of random masked actions. Microseconds per step, on this machine: compare the
parts with each other, not with another machine's figures.
"""

from __future__ import annotations

import sys
import time
from collections import defaultdict
from collections.abc import Callable
from typing import Any

import numpy as np

from decoy_cli.bench.machine import machine_line
from decoy_cli.bench.portable import _play
from decoy_cli.damage import load_damage_model
from decoy_cli.env import DecoyParallelEnv
from decoy_cli.env import step as env_step
from decoy_cli.env.array_env import DecoyArrayEnv
from decoy_cli.sim.combat import CombatStep
from decoy_cli.sim.engine import Simulator

SPENT: dict[str, float] = defaultdict(float)


def timed(owner: Any, name: str, label: str) -> None:
    """Wrap `owner.name` (a class's method or a module's function) so that its time adds up in
    SPENT[label]."""
    method: Callable[..., Any] = getattr(owner, name)

    def wrapper(*args: Any, **kwargs: Any) -> Any:
        started = time.perf_counter()
        try:
            return method(*args, **kwargs)
        finally:
            SPENT[label] += time.perf_counter() - started

    setattr(owner, name, wrapper)


def main() -> None:
    rounds = int(sys.argv[1]) if len(sys.argv) > 1 else 5
    for owner, name, label in ((DecoyParallelEnv, "step", "step"),
                               (DecoyParallelEnv, "_observe", "_observe"),
                               (DecoyParallelEnv, "_infos", "_infos"),
                               (DecoyArrayEnv, "step", "game"),
                               (env_step, "_quiet_step", "quiet"), (Simulator, "step", "whole"),
                               (CombatStep, "run", "combat"),
                               (env_step.RoundSteps, "_finish", "finish"),
                               (env_step.RoundSteps, "state", "first"),
                               (env_step.RoundSteps, "_quiet_from_here", "shared")):  # fmt: skip
        timed(owner, name, label)
    env = DecoyParallelEnv(mover="kinematic", damage_model=load_damage_model("shipped"))
    rng = np.random.default_rng(0)
    _play(env, rng, seed=0)  # warm-up: compilation
    SPENT.clear()
    started = time.perf_counter()
    played = [_play(env, rng, seed=k + 1) for k in range(rounds)]
    wall = time.perf_counter() - started
    env.close()
    steps = sum(p["steps"] for p in played)
    decisions = sum(p["decisions"] for p in played)
    per = {name: seconds / steps * 1e6 for name, seconds in SPENT.items()}
    print(machine_line())
    print(f"{rounds} rounds, {steps:,} steps, {decisions:,} decisions, {decisions / wall:,.0f} "
          f"decisions/s (wrapping adds a little to each part)")  # fmt: skip
    parts = {
        "the whole step": wall / steps * 1e6,
        "  env.step (PettingZoo)": per["step"],
        "    the game's step (DecoyArrayEnv)": per["game"],
        "      compiled quiet stretches": per["quiet"],
        "      whole ticks in Python (Simulator.step)": per["whole"],
        "        of them the combat steps": per["combat"],
        "      the state after steps ended in Python": per["finish"] - per["first"],
        "      the quiet steps' shared state": per["shared"],
        "      the game step's own Python": (
            per["game"]
            - per["quiet"]
            - per["whole"]
            - (per["finish"] - per["first"])
            - per["shared"]
        ),
        "    observation dictionaries": per["_observe"],
        "    info dictionaries": per["_infos"],
        "    the PettingZoo step's own Python": (
            per["step"] - per["game"] - per["_observe"] - per["_infos"]
        ),
        "  the benchmark's own loop": wall / steps * 1e6 - per["step"],
    }
    for part, micros in parts.items():
        print(f"{part:<52} {micros:7.1f} us/step")


if __name__ == "__main__":
    main()
