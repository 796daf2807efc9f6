"""Training at scale: the environment from picklable settings, and its Ray RLlib adapter.

* factory.py: `env_from_config`, the factory every worker of a distributed trainer calls;
* rllib_env.py: `DecoyRLlibEnv`, RLlib's multi-agent env over `DecoyParallelEnv`, and the
  callback that reports who won (needs `pip install -e ".[rl]"`).

`examples/rllib_ppo.py` trains a shared PPO policy with them.
"""
