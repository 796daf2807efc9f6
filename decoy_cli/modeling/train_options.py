"""How DIP and DOG are trained: the options and their defaults, defined once (no torch here, so
the CLI can show them as option defaults without importing torch).

Defaults are the paper's (decoy_checkpoints/dip_args.json and dog_args.json): learning rate
3e-4, batch size 256, 20 epochs for DIP and 50 for DOG, Xavier-uniform initialisation, DOG loss
weights 1 (damage MSE), 0.7 (hit-group cross-entropy) and 0.2 (KL); plus early stopping after
`PATIENCE` epochs without a better validation loss, and one torch thread (these networks are
small; thread hand-offs cost more than they save on small batches).
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass
from typing import Literal, get_args

from decoy_cli.errors import DecoyError
from decoy_cli.modeling.split import DEFAULT_SEED

DIP_EPOCHS = 20
DOG_EPOCHS = 50
BATCH_SIZE = 256
LEARNING_RATE = 3e-4
PATIENCE = 5
THREADS = 1
XAVIER = True

DAMAGE_WEIGHT = 1.0
HIT_GROUP_WEIGHT = 0.7
KL_WEIGHT = 0.2

Balance = Literal["all", "eval", "none"]
BALANCE: tuple[Balance, ...] = get_args(Balance)
"""DIP's 1:1 balancing: every part (the paper's), validation and test only (train on all
samples), or none."""
DEFAULT_BALANCE: Balance = "all"


@dataclass(frozen=True, kw_only=True)
class TrainOptions:
    """How to train one network; every value is checked here, so a bad one is one DecoyError
    line before any data is read."""

    epochs: int = DIP_EPOCHS
    batch_size: int = BATCH_SIZE
    learning_rate: float = LEARNING_RATE
    patience: int = PATIENCE
    seed: int = DEFAULT_SEED
    xavier: bool = XAVIER
    threads: int = THREADS

    def __post_init__(self) -> None:
        if self.epochs < 1:
            raise DecoyError(f"epochs must be at least 1, not {self.epochs}")
        if self.batch_size < 2:
            raise DecoyError(f"the batch size must be at least 2, not {self.batch_size}")
        if not (math.isfinite(self.learning_rate) and self.learning_rate > 0):
            raise DecoyError(f"the learning rate must be positive, not {self.learning_rate}")
        if self.patience < 1:
            raise DecoyError(f"patience must be at least 1 epoch, not {self.patience}")
        if self.threads < 1:
            raise DecoyError(f"threads must be at least 1, not {self.threads}")

    def to_json(self) -> dict[str, object]:
        """The options as a JSON-ready dict (kept in a trained model's metadata)."""
        return asdict(self)


@dataclass(frozen=True, kw_only=True)
class DogLossWeights:
    """Weights of DOG's loss terms (`losses.dog_loss`); none may be negative."""

    damage: float = DAMAGE_WEIGHT
    hit_group: float = HIT_GROUP_WEIGHT
    kl: float = KL_WEIGHT

    def __post_init__(self) -> None:
        for name, value in (("damage", self.damage), ("hit-group", self.hit_group)):
            if not value >= 0:
                raise DecoyError(f"the {name} weight must not be negative, not {value}")
        if not self.kl >= 0:
            raise DecoyError(f"the KL weight must not be negative, not {self.kl}")

    def to_json(self) -> dict[str, float]:
        """The weights as a JSON-ready dict."""
        return asdict(self)
