"""`env_from_config`: a `DecoyParallelEnv` from plain settings a trainer can pickle and ship.

A distributed trainer (Ray RLlib's env runners, a process pool, a cluster) sends each worker a
function and a dictionary, not an environment: a pybullet client and torch models do not
travel. The worker calls `env_from_config(settings)` and builds its own environment, loading the
damage models itself.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from decoy_cli.damage import DEFAULT_MODELS
from decoy_cli.env.parallel import DecoyParallelEnv

ENV_SETTINGS = ("map", "n_t", "n_ct", "mover", "models", "combat", "bomb", "stop_seconds")
"""The settings `env_from_config` reads; "models" names the damage models as `--models` does."""


def env_from_config(config: Mapping[str, Any] | None = None) -> DecoyParallelEnv:
    """An environment from `ENV_SETTINGS`: "models" is "rules" (default), "shipped", "none" or a
    model folder, loaded here; the others are `DecoyParallelEnv`'s arguments. An unknown key is
    a ValueError, so a typo does not silently train the default."""
    settings = dict(config or {})
    unknown = sorted(set(settings) - set(ENV_SETTINGS))
    if unknown:
        raise ValueError(f"unknown environment settings {unknown} (known: {list(ENV_SETTINGS)})")
    models = str(settings.pop("models", DEFAULT_MODELS))

    def load():
        from decoy_cli.damage import load_damage_model

        return load_damage_model(models)

    return DecoyParallelEnv(damage_model=load, **settings)
