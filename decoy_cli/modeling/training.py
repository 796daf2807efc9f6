"""Training DIP and DOG (torch: imported by the training command only).

Both use Adam, mini-batches shuffled each epoch, and early stopping on the validation split:
after every epoch the validation loss is measured (eval mode); the weights of the best epoch
are kept and returned, and training stops when `patience` epochs in a row did not improve it.
The options and their defaults (the paper's) are in train_options.py, without torch.

* DIP: binary cross-entropy on "the attacker damaged the victim in this step".
* DOG: `losses.dog_loss` on the damaging pairs: damage in HP/100, hit-group code.

Determinism: everything random (initial weights, shuffling, dropout, the VAE's noise) comes from
torch generators seeded with `TrainOptions.seed`, inside `torch.random.fork_rng`, so the same
data and options give the same weights and the caller's global torch RNG is left as it was.
The validation loss of DOG draws its noise from a generator reset every epoch, so epochs are
compared on the same noise.

Threads: training runs with `TrainOptions.threads` torch threads (default 1; restored after).
These networks and their batches are small, so thread hand-offs dominate and more threads only
pay off for large batches.
"""

from __future__ import annotations

import copy
import math
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from dataclasses import dataclass, field
from typing import Generic, TypeVar, cast

import numpy as np
import torch
import torch.nn.functional as F
from torch import Tensor, nn

from decoy_cli.damage.features import HIT_GROUPS, Features, FeatureSpec
from decoy_cli.damage.model_folder import LoadedDip, LoadedDog
from decoy_cli.damage.networks import DipNet, DogNet, tensors
from decoy_cli.errors import DecoyError
from decoy_cli.modeling.losses import dog_loss
from decoy_cli.modeling.network_evaluation import (
    DRAWS,
    DipEvaluation,
    DogEvaluation,
    dip_probabilities,
    evaluate_dip,
    evaluate_dog,
)
from decoy_cli.modeling.sample_set import Samples
from decoy_cli.modeling.scores import MIN_CELL, best_f1_threshold
from decoy_cli.modeling.split import Split, balance
from decoy_cli.modeling.train_options import (
    BALANCE,
    DEFAULT_BALANCE,
    Balance,
    DogLossWeights,
    TrainOptions,
)


@dataclass(frozen=True)
class EpochRecord:
    """One epoch: mean training loss, validation loss (and DOG's validation loss terms)."""

    epoch: int
    train_loss: float
    val_loss: float
    val_parts: dict[str, float] = field(default_factory=dict)
    best: bool = False


@dataclass(frozen=True)
class Progress:
    """Where training is: after each batch (`record` None) and after each epoch (its record)."""

    epoch: int
    epochs: int
    batch: int
    batches: int
    record: EpochRecord | None = None


@dataclass
class Trained:
    """A trained network in eval mode holding its best epoch's weights, and the history."""

    net: nn.Module
    history: list[EpochRecord]
    best_epoch: int
    stopped_early: bool


ProgressCallback = Callable[[Progress], None]


def _xavier(net: nn.Module) -> None:
    """Xavier-uniform weights and zero biases for every Linear layer (the paper's init)."""
    for module in net.modules():
        if isinstance(module, nn.Linear):
            nn.init.xavier_uniform_(module.weight)
            nn.init.zeros_(module.bias)


@contextmanager
def _threads(count: int) -> Iterator[None]:
    """torch's intra-op thread count set to `count` inside the block, restored after."""
    before = torch.get_num_threads()
    torch.set_num_threads(count)
    try:
        yield
    finally:
        torch.set_num_threads(before)


def _batches(count: int, size: int, generator: torch.Generator) -> list[Tensor]:
    """A shuffled epoch in batches; a last batch of one sample is dropped (BatchNorm needs 2)."""
    order = torch.randperm(count, generator=generator)
    parts = list(torch.split(order, size))
    return [p for p in parts if len(p) > 1]


def _fit(
    net: nn.Module,
    count: int,
    train_step: Callable[[Tensor], Tensor],
    val_loss: Callable[[], tuple[float, dict[str, float]]],
    options: TrainOptions,
    progress: ProgressCallback | None,
) -> Trained:
    """The loop both networks share (module docstring)."""
    optimizer = torch.optim.Adam(net.parameters(), lr=options.learning_rate)
    shuffle = torch.Generator().manual_seed(options.seed)
    history: list[EpochRecord] = []
    best_loss, best_epoch, best_state, waited = math.inf, 0, None, 0
    stopped_early = False
    for epoch in range(1, options.epochs + 1):
        net.train()
        batches = _batches(count, options.batch_size, shuffle)
        total, seen = 0.0, 0
        for b, index in enumerate(batches, start=1):
            optimizer.zero_grad()
            loss = train_step(index)
            loss.backward()
            optimizer.step()
            total += float(loss.detach()) * len(index)
            seen += len(index)
            if progress is not None:
                progress(Progress(epoch, options.epochs, b, len(batches)))
        net.eval()
        with torch.no_grad():
            loss_value, parts = val_loss()
        improved = loss_value < best_loss
        if improved:
            best_loss, best_epoch, waited = loss_value, epoch, 0
            best_state = copy.deepcopy(net.state_dict())
        else:
            waited += 1
        record = EpochRecord(epoch, total / max(seen, 1), loss_value, parts, improved)
        history.append(record)
        if progress is not None:
            progress(Progress(epoch, options.epochs, len(batches), len(batches), record))
        if waited >= options.patience:
            stopped_early = epoch < options.epochs
            break
    if best_state is not None:
        net.load_state_dict(best_state)
    net.eval()
    return Trained(net, history, best_epoch, stopped_early)


def _need(features: Features, minimum: int, what: str) -> None:
    if len(features) < minimum:
        raise DecoyError(f"{what} has {len(features)} samples, training needs at least {minimum}")


def train_dip(
    train: Features,
    train_labels: np.ndarray,
    val: Features,
    val_labels: np.ndarray,
    options: TrainOptions,
    progress: ProgressCallback | None = None,
) -> Trained:
    """DIP trained with binary cross-entropy; the best epoch by validation loss is kept."""
    _need(train, 2, "the training split")
    _need(val, 1, "the validation split")
    x_train, x_val = tensors(train), tensors(val)
    y_train = torch.from_numpy(np.asarray(train_labels, dtype=np.float32))
    y_val = torch.from_numpy(np.asarray(val_labels, dtype=np.float32))
    with torch.random.fork_rng(devices=[]), _threads(options.threads):
        torch.manual_seed(options.seed)
        net = DipNet()
        if options.xavier:
            _xavier(net)

        def step(index: Tensor) -> Tensor:
            logits = net(*(x[index] for x in x_train))
            return F.binary_cross_entropy_with_logits(logits, y_train[index])

        def validate() -> tuple[float, dict[str, float]]:
            loss = F.binary_cross_entropy_with_logits(net(*x_val), y_val)
            return float(loss), {}

        return _fit(net, len(train), step, validate, options, progress)


def _onehot(codes: np.ndarray) -> tuple[Tensor, Tensor]:
    """Hit-group codes as an int64 tensor and its one-hot floats."""
    index = torch.from_numpy(np.asarray(codes, dtype=np.int64))
    if len(index) and (int(index.min()) < 0 or int(index.max()) >= len(HIT_GROUPS)):
        raise ValueError("DOG trains on damaging samples only (hit groups 0..5)")
    return index, F.one_hot(index, len(HIT_GROUPS)).float()


def train_dog(
    train: Features,
    train_damage_hp: np.ndarray,
    train_group: np.ndarray,
    val: Features,
    val_damage_hp: np.ndarray,
    val_group: np.ndarray,
    options: TrainOptions,
    weights: DogLossWeights | None = None,
    progress: ProgressCallback | None = None,
) -> Trained:
    """DOG trained with the weighted damage, hit-group and KL loss on damaging samples; the
    best epoch by validation loss is kept."""
    weights = weights or DogLossWeights()
    _need(train, 2, "the training split")
    _need(val, 1, "the validation split")
    x_train, x_val = tensors(train), tensors(val)
    d_train = torch.from_numpy(np.asarray(train_damage_hp, dtype=np.float32) / 100.0)[:, None]
    d_val = torch.from_numpy(np.asarray(val_damage_hp, dtype=np.float32) / 100.0)[:, None]
    g_train, h_train = _onehot(train_group)
    g_val, h_val = _onehot(val_group)
    with torch.random.fork_rng(devices=[]), _threads(options.threads):
        torch.manual_seed(options.seed)
        net = DogNet()
        if options.xavier:
            _xavier(net)
        noise = torch.Generator().manual_seed(options.seed + 1)

        def step(index: Tensor) -> Tensor:
            out = net(d_train[index], h_train[index], *(x[index] for x in x_train), noise)
            loss, _ = dog_loss(out, d_train[index], g_train[index], weights)
            return loss

        def validate() -> tuple[float, dict[str, float]]:
            fixed = torch.Generator().manual_seed(options.seed + 2)
            out = net(d_val, h_val, *x_val, generator=fixed)
            loss, parts = dog_loss(out, d_val, g_val, weights)
            return float(loss), parts

        return _fit(net, len(train), step, validate, options, progress)


# ---- a whole run: split, train, threshold, test ----------------------------------------------


EvaluationT = TypeVar("EvaluationT", bound=DipEvaluation | DogEvaluation)
ModelT = TypeVar("ModelT", bound=LoadedDip | LoadedDog)


@dataclass
class Run(Generic[EvaluationT, ModelT]):
    """A trained model with the indices of its split parts (into the samples), its training
    history and its evaluation on the test part (`DipRun` or `DogRun`)."""

    trained: Trained
    parts: dict[str, np.ndarray]
    test: EvaluationT
    model: ModelT

    def summary(self) -> dict[str, object]:
        """Sizes, best epoch and test metrics as a JSON-ready dict."""
        return {
            "samples": {name: len(index) for name, index in self.parts.items()},
            "best_epoch": self.trained.best_epoch,
            "epochs_run": len(self.trained.history),
            "stopped_early": self.trained.stopped_early,
            "test_metrics": {k: v for k, v in self.test.metrics.items() if k != "cells"},
        }


DipRun = Run[DipEvaluation, LoadedDip]
DogRun = Run[DogEvaluation, LoadedDog]


def dip_parts(
    samples: Samples, split: Split, balanced: Balance, seed: int
) -> dict[str, np.ndarray]:
    """Train, validation and test indices for DIP, balanced 1:1 with the seed as `balanced`
    says (BALANCE)."""
    if balanced not in BALANCE:
        raise DecoyError(f"balance must be one of {', '.join(BALANCE)}, not {balanced!r}")
    parts = {name: split.part(name) for name in ("train", "val", "test")}
    for name, index in parts.items():
        if balanced == "all" or (balanced == "eval" and name != "train"):
            parts[name] = balance(samples, index, seed)
    return parts


def dog_parts(samples: Samples, split: Split) -> dict[str, np.ndarray]:
    """Train, validation and test indices for DOG: the damaging samples of each part whose raw
    damage and hit group are known."""
    parts = {name: split.part(name) for name in ("train", "val", "test")}
    known = samples.outcome_known
    return {name: index[known[index]] for name, index in parts.items()}


def fit_dip(
    samples: Samples,
    split: Split,
    options: TrainOptions,
    spec: FeatureSpec,
    balanced: Balance = DEFAULT_BALANCE,
    progress: ProgressCallback | None = None,
) -> DipRun:
    """Train DIP on the training part, choose its threshold by the best F1 on the validation
    part, and evaluate it on the test part."""
    parts = dip_parts(samples, split, balanced, options.seed)
    for name, index in parts.items():
        if not samples.hit[index].any():
            raise DecoyError(f"the {name} split has no damaging samples: use more data")
    features = {name: samples.take(index).features(spec) for name, index in parts.items()}
    trained = train_dip(
        features["train"],
        samples.hit[parts["train"]],
        features["val"],
        samples.hit[parts["val"]],
        options,
        progress,
    )
    model = LoadedDip(cast(DipNet, trained.net), spec, 0.5)
    val = samples.take(parts["val"])
    model.threshold = best_f1_threshold(val.hit, dip_probabilities(model, val))
    test = evaluate_dip(model, samples.take(parts["test"]))
    return Run(trained, parts, test, model)


def fit_dog(
    samples: Samples,
    split: Split,
    options: TrainOptions,
    spec: FeatureSpec,
    weights: DogLossWeights | None = None,
    draws: int = DRAWS,
    min_cell: int = MIN_CELL,
    progress: ProgressCallback | None = None,
) -> DogRun:
    """Train DOG on the damaging samples of the training part (early stopping on those of the
    validation part) and evaluate it on those of the test part."""
    parts = dog_parts(samples, split)
    for name, index in parts.items():
        if len(index) == 0:
            raise DecoyError(f"the {name} split has no damaging samples: use more data")
    train, val = samples.take(parts["train"]), samples.take(parts["val"])
    trained = train_dog(
        train.features(spec),
        train.damage,
        train.hit_group,
        val.features(spec),
        val.damage,
        val.hit_group,
        options,
        weights,
        progress,
    )
    model = LoadedDog(cast(DogNet, trained.net), spec)
    test = evaluate_dog(model, samples.take(parts["test"]), options.seed, draws, min_cell)
    return Run(trained, parts, test, model)
