"""Bench sections that run from this file on any version's code: the kinematic core, the
environment, the combat step and the metrics, measured the same way on the current code and on
a baseline that predates them.

`decoy bench --baseline REF` runs each section in a fresh process of either code tree. The
sections here use only what every version of the benchmark offers (`speed_table` and `NeverHits`
of `decoy_cli.bench.simspeed`, `step_costs` and `summarize_ms` of `decoy_cli.bench.combat`,
`metric_throughput` and `walk` of `decoy_cli.bench.metrics`, `dtw` and `frechet` of
`decoy_cli.metrics`, `DecoyParallelEnv`, `load_damage_model`), so the baseline's process loads
this file by path (`baseline.DRIVER`) and its imports resolve to the baseline's package: one
measuring code, two simulators. Their sizes come from the settings (`PortableConfig`, made from
the current code's `BenchConfig`), so both sides measure the same amount of work.

* `kinematic`: the Table 1 protocol at 10 agents with the kinematic mover, whose engine plays
  event by event (`Simulator.run`);
* `env`: agent decisions per second through the PettingZoo environment, 5 T against 5 CT,
  combat with the chosen damage model, the bomb on, each agent that needs a decision taking a
  uniformly random allowed action (its action mask); how far the environment raises the
  process's peak resident memory is reported beside it. Where the code has the array
  environment under it (`DecoyArrayEnv`), rounds from the same seeds are also played through
  that, the random masked actions drawn for all agents at once as a batched trainer would (so
  the rounds part after the first decisions; against a baseline without it, the ratio is of
  the array interface to the baseline's PettingZoo one: an interface change as much as a
  speed-up);
* `combat_step`: one combat step in its parts at each agent count asked (half T, half CT),
  spread over the map and clustered (`decoy_cli.bench.combat`); larger counts take
  proportionally fewer steps, at least `MIN_COMBAT_STEPS`;
* `metrics`: the throughput of the ten fidelity metrics on synthetic player-rounds, and the
  exact DTW and discrete Fréchet kernels alone on a pair of the longest ESTA rounds' length
  and on one of the paper protocol's length (`KERNEL_FRAMES`).
"""

from __future__ import annotations

import time
from collections.abc import Callable
from typing import TYPE_CHECKING, TypedDict

import numpy as np

if TYPE_CHECKING:  # types only: this file also runs on versions without these modules
    from decoy_cli.bench.records import (
        ArrayFigures,
        CombatResult,
        CombatRow,
        EnvResult,
        KernelRow,
        KinematicResult,
        MetricsResult,
        PortableConfig,
    )
    from decoy_cli.env import DecoyArrayEnv, DecoyParallelEnv
    from decoy_cli.sim.combat import DamageModel

KINEMATIC_AGENTS = 10
"""The agent count of the kinematic row (the issue's and the paper's middle row)."""

ENV_ROUNDS = 5
"""Timed environment rounds (one more, untimed, warms up the compiled code)."""

COMBAT_AGENTS = 10
"""The combat step's default agent count (5v5), whose steps are `combat_repeats`."""

MIN_COMBAT_STEPS = 5
"""The fewest timed steps of a crowded combat step."""

KERNEL_FRAMES = (310, 451)
"""Curve lengths of the kernel timings: the longest ESTA rounds at 2 Hz, the paper protocol's."""


class _TableMap(TypedDict, total=False):
    """`speed_table`'s map, passed only off the built-in map (earlier versions know none)."""

    map_name: str


class _EnvMap(TypedDict, total=False):
    """The environment's map, passed only off the built-in map (as `_TableMap`)."""

    map: str


def kinematic_section(config: PortableConfig) -> KinematicResult:
    """Table 1's protocol at `KINEMATIC_AGENTS` agents with the kinematic mover."""
    from decoy_cli.bench.simspeed import speed_table

    decisions = int(config.get("decisions", 1_000 if config.get("quick") else 10_000))
    model, label = _model(config)
    on_map: _TableMap = {"map_name": config["map"]} if "map" in config else {}
    rows = speed_table(
        (KINEMATIC_AGENTS,),
        decisions,
        model,
        mover="kinematic",
        combat=bool(config.get("combat", True)),
        bomb=bool(config.get("bomb", True)),
        seed=int(config.get("seed", 0)),
        **on_map,
    )
    row = rows[0].to_dict()
    return {
        "agents": KINEMATIC_AGENTS,
        "decisions": row["decisions"],
        "ticks": row["ticks"],
        "wall_s": row["wall_s"],
        "ticks_per_s": row["ticks_per_s"],
        "time_scale": row["time_scale"],
        "damage_model": label,
    }


def env_section(config: PortableConfig) -> EnvResult:
    """Random masked 5v5 rounds through `DecoyParallelEnv` (module docstring)."""
    from decoy_cli.bench.machine import peak_rss_mb

    try:
        from decoy_cli.env import DecoyParallelEnv
    except ImportError:  # a version from before the environments left decoy_cli.sim
        from decoy_cli.sim import DecoyParallelEnv  # type: ignore[no-redef]

    rounds = 1 if config.get("quick") else ENV_ROUNDS
    rng = np.random.default_rng(int(config.get("seed", 0)))
    model, label = _model(config)
    before = peak_rss_mb()
    on_map: _EnvMap = {"map": config["map"]} if "map" in config else {}
    env = DecoyParallelEnv(mover="kinematic", damage_model=model, n_t=5, n_ct=5, **on_map)
    try:
        _play(env, rng, seed=0)  # warm-up: compilation and caches
        started = time.perf_counter()
        cpu = time.process_time()
        totals = [_play(env, rng, seed=k + 1) for k in range(rounds)]
        wall = time.perf_counter() - started
        cpu = time.process_time() - cpu
        grown = peak_rss_mb() - before
    finally:
        env.close()
    decisions = sum(t["decisions"] for t in totals)
    arrays = _array_rounds(config, model, rounds)
    return {
        **arrays,
        "rounds": rounds,
        "mover": "kinematic",
        "decisions": decisions,
        "steps": sum(t["steps"] for t in totals),
        "game_s": sum(t["game_s"] for t in totals),
        "outcomes": [t["outcome"] for t in totals],
        "wall_s": wall,
        "cpu_s": cpu,
        "decisions_per_s": decisions / wall,
        "env_memory_mb": grown,
        "damage_model": label,
    }


class _Played(TypedDict):
    """One round of `_play`."""

    decisions: int
    steps: int
    game_s: float
    outcome: str


def _play(env: DecoyParallelEnv, rng: np.random.Generator, seed: int) -> _Played:
    """One round of random masked actions; its decisions, steps, game time and outcome."""
    obs, infos = env.reset(seed=seed)
    decisions = steps = 0
    tick = 0
    outcome = ""
    while env.agents:
        actions = {}
        for name in env.agents:
            if infos[name]["needs_decision"]:
                allowed = np.flatnonzero(obs[name]["action_mask"])
                actions[name] = int(allowed[int(rng.random() * len(allowed))])
        decisions += len(actions)
        obs, _, _, _, infos = env.step(actions)
        steps += 1
        for info in infos.values():
            tick = max(tick, int(info["tick"]))
            outcome = str(info.get("reason", outcome))
    return {"decisions": decisions, "steps": steps, "game_s": tick / 60.0, "outcome": outcome}


def _array_rounds(config: PortableConfig, model: DamageModel | None, rounds: int) -> ArrayFigures:
    """The environment section's rounds through `DecoyArrayEnv`, if this code has it."""
    try:
        from decoy_cli.env.array_env import DecoyArrayEnv
    except ImportError:
        try:  # a version from before the environments left decoy_cli.sim
            from decoy_cli.sim.array_env import (  # type: ignore[no-redef]
                DecoyArrayEnv,
            )
        except ImportError:  # a version without the array environment
            return {}
    rng = np.random.default_rng(int(config.get("seed", 0)))
    env = DecoyArrayEnv(mover="kinematic", damage_model=model, n_t=5, n_ct=5, map=config.get("map"))
    try:
        _play_arrays(env, rng, seed=0)  # warm-up
        started = time.perf_counter()
        totals = [_play_arrays(env, rng, seed=k + 1) for k in range(rounds)]
        wall = time.perf_counter() - started
    finally:
        env.close()
    decisions = sum(totals)
    return {
        "array_decisions": decisions,
        "array_wall_s": wall,
        "array_decisions_per_s": decisions / wall,
    }


def _play_arrays(env: DecoyArrayEnv, rng: np.random.Generator, seed: int) -> int:
    """One round of random masked actions through the array environment; its decisions."""
    state = env.reset(seed)
    decisions = 0
    while state.winner is None:
        masks = state.action_masks
        decisions += int(state.needs_decision.sum())
        state = env.step(np.argmax(rng.random(masks.shape) * masks, axis=1))
    return decisions


def _builtin_map() -> str:
    """The map a section plays when the settings name none."""
    try:
        from decoy_cli.csgo import BUILTIN_MAP
    except ImportError:  # a version from before the one map constant
        return "de_dust2"
    return BUILTIN_MAP


def _model(config: PortableConfig) -> tuple[DamageModel | None, str]:
    """The damage model the config names and how the report names it (None: "none", or a
    model that did not load, said so; the section then runs without shooting)."""
    from decoy_cli.damage import load_damage_model

    models = str(config.get("models", "shipped"))
    if models == "none":
        return None, "none"
    try:
        return load_damage_model(models), models
    except Exception as error:  # any version's loading error: reported, the section goes on
        return None, f"none ({models} did not load: {error})"


def combat_section(config: PortableConfig) -> CombatResult:
    """The combat step's parts at each agent count of the settings (module docstring)."""
    from decoy_cli.bench.combat import step_costs
    from decoy_cli.bench.simspeed import NeverHits

    model, label = _model(config)
    repeats = int(config.get("combat_repeats", 20 if config.get("quick") else 300))
    on_map: _TableMap = {"map_name": config["map"]} if "map" in config else {}
    rows: list[CombatRow] = []
    for agents in config.get("combat_agents", [COMBAT_AGENTS]):
        steps = repeats * COMBAT_AGENTS // max(agents, COMBAT_AGENTS)
        rows += step_costs(
            model or NeverHits(),
            agents // 2,
            max(steps, MIN_COMBAT_STEPS),
            int(config.get("seed", 0)),
            **on_map,
        )
    return {"map": config.get("map", _builtin_map()), "damage_model": label, "rows": rows}


def metrics_section(config: PortableConfig) -> MetricsResult:
    """The metric throughput and the distance kernels (module docstring)."""
    from decoy_cli.bench.metrics import metric_throughput

    pairs = int(config.get("metric_pairs", 100 if config.get("quick") else 2000))
    result: MetricsResult = metric_throughput(pairs, int(config.get("seed", 0)))
    repeats = int(config.get("kernel_repeats", 50 if config.get("quick") else 500))
    result["kernels"] = kernel_times(repeats, int(config.get("seed", 0)))
    return result


def kernel_times(repeats: int, seed: int = 0) -> list[KernelRow]:
    """Wall times of `dtw`, `frechet` and `frechet` on x-y alone, each on one pair of random
    walks of every `KERNEL_FRAMES` length, after a call that compiles or loads the kernel."""
    from decoy_cli.bench.combat import summarize_ms
    from decoy_cli.bench.metrics import walk
    from decoy_cli.metrics import dtw, frechet

    rng = np.random.default_rng(seed)
    rows: list[KernelRow] = []
    for frames in KERNEL_FRAMES:
        a, b = walk(rng, frames), walk(rng, frames)
        for kernel, call, first, second in (
            ("dtw", dtw, a, b),
            ("frechet", frechet, a, b),
            ("frechet x-y", frechet, a[:, :2], b[:, :2]),
        ):
            call(first, second)
            times = []
            for _ in range(repeats):
                started = time.perf_counter()
                call(first, second)
                times.append(time.perf_counter() - started)
            rows.append(
                {
                    "kernel": kernel,
                    "size": f"{frames}x{frames}",
                    "calls": repeats,
                    **summarize_ms(times),
                }
            )
    return rows


PORTABLE_SECTIONS: dict[
    str, Callable[[PortableConfig], KinematicResult | EnvResult | CombatResult | MetricsResult]
] = {
    "kinematic": kinematic_section,
    "env": env_section,
    "combat_step": combat_section,
    "metrics": metrics_section,
}
"""The sections this file runs, by name."""
