"""Train one shared PPO policy for both teams on de_dust2 with Ray RLlib, action masking on.

    pip install -e ".[rl]"
    python examples/rllib_ppo.py --iterations 20 --env-runners 2
    python examples/rllib_ppo.py --address auto --env-runners 16   # on a running Ray cluster

Every agent of both sides acts through the same RL module (the observation says which side it
is on, `is_ct`); RLlib's action-masking module keeps each agent to the moves its waypoint has.
Only agents that need a decision act (`decoy_cli.rl.rllib_env`). Each env runner builds its own
environment from plain settings (`decoy_cli.rl.factory.env_from_config`), so the same script
runs on one machine or on a cluster: start Ray on the nodes (`ray start --head` on one,
`ray start --address HEAD:6379` on the others), then pass `--address auto` from a node of the
cluster; `--env-runners` counts runners across the cluster, one CPU each.

Per iteration it prints the episodes that ended, T's win rate among them, the mean round length,
the env steps and agent decisions sampled, and the sampling throughput: agent decisions per
second of sampling time, and per second of the whole iteration (sampling plus learning).
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from decoy_cli.damage import CHOICES_HELP, DEFAULT_MODELS


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--iterations", type=int, default=10, help="training iterations")
    parser.add_argument(
        "--env-runners", type=int, default=1, help="sampling workers, one CPU each (0: sample in "
        "the driver)"
    )  # fmt: skip
    parser.add_argument("--address", default=None, help="a running Ray cluster ('auto', host:port)")
    parser.add_argument("--batch", type=int, default=4000, help="env steps per iteration")
    parser.add_argument("--map", default="dust2", help="a built-in map: dust2, mirage, ...")
    parser.add_argument("--mover", choices=("kinematic", "physics"), default="kinematic")
    parser.add_argument("--models", default=DEFAULT_MODELS, help=f"damage models: {CHOICES_HELP}")
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args()
    if args.iterations < 1 or args.env_runners < 0 or args.batch < 8:
        parser.error("need --iterations >= 1, --env-runners >= 0 and --batch >= 8")

    import ray
    from ray.rllib.algorithms.ppo import PPOConfig
    from ray.rllib.core.rl_module.multi_rl_module import MultiRLModuleSpec
    from ray.rllib.core.rl_module.rl_module import RLModuleSpec
    from ray.rllib.examples.rl_modules.classes.action_masking_rlm import (
        ActionMaskingTorchRLModule,
    )

    from decoy_cli.rl.rllib_env import DecoyRLlibEnv, WinRates

    if args.address:
        ray.init(address=args.address, log_to_driver=False)
    else:
        ray.init(num_cpus=max(2, args.env_runners + 1), include_dashboard=False,
                 log_to_driver=False)  # fmt: skip
    module = RLModuleSpec(
        module_class=ActionMaskingTorchRLModule, model_config={"head_fcnet_hiddens": [64, 64]}
    )
    config = (
        PPOConfig()
        .environment(
            DecoyRLlibEnv, env_config={"map": args.map, "mover": args.mover, "models": args.models}
        )
        .multi_agent(policies={"shared"}, policy_mapping_fn=lambda agent, episode, **kw: "shared")
        .rl_module(rl_module_spec=MultiRLModuleSpec(rl_module_specs={"shared": module}))
        .env_runners(num_env_runners=args.env_runners)
        .training(
            train_batch_size_per_learner=args.batch,
            minibatch_size=max(4, args.batch // 4),
            num_epochs=2,
        )
        .callbacks(WinRates)
        .debugging(seed=args.seed)
    )
    algo = config.build_algo()
    print(
        f"{'iter':>4} {'episodes':>8} {'T win':>6} {'round s':>7} {'env steps':>9} "
        f"{'decisions':>9} {'sample s':>8} {'iter s':>7} {'dec/s sample':>12} {'dec/s iter':>10}"
    )
    try:
        for _ in range(args.iterations):
            started = time.perf_counter()
            result = algo.train()
            wall = time.perf_counter() - started
            runners = result["env_runners"]
            decisions = _total(runners.get("num_agent_steps_sampled", {}))
            sampling = float(result["timers"]["env_runner_sampling_timer"])
            episodes = int(np.nan_to_num(float(runners.get("num_episodes", 0))))
            win = float(runners.get("t_win_rate", np.nan)) if episodes else np.nan
            length = float(runners.get("round_s", np.nan)) if episodes else np.nan
            print(
                f"{result['training_iteration']:>4} {episodes:>8} {win:>6.2f} {length:>7.1f} "
                f"{int(runners['num_env_steps_sampled']):>9} {decisions:>9} {sampling:>8.2f} "
                f"{wall:>7.2f} {decisions / sampling:>12,.0f} {decisions / wall:>10,.0f}",
                flush=True,
            )
    finally:
        algo.stop()
        ray.shutdown()


def _total(counts: object) -> int:
    """Agent steps sampled: RLlib reports them per agent (a dict) or as one number."""
    if isinstance(counts, dict):
        return int(sum(float(np.asarray(v)) for v in counts.values()))
    return int(float(np.asarray(counts)))


if __name__ == "__main__":
    main()
