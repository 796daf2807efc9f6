"""Training DIP and DOG (decoy_cli/modeling/training.py) on small generated datasets with a
planted signal: the models must learn it, deterministically under a seed, keeping the best
epoch."""

from __future__ import annotations

import numpy as np
import pytest
import torch
import torch.nn.functional as F

from decoy_cli.damage.features import FeatureSpec
from decoy_cli.damage.model_folder import LoadedDip, LoadedDog
from decoy_cli.damage.networks import tensors
from decoy_cli.errors import DecoyError
from decoy_cli.modeling.network_evaluation import dip_probabilities, evaluate_dog
from decoy_cli.modeling.samples import Samples, split_samples
from decoy_cli.modeling.scores import roc_auc
from decoy_cli.modeling.training import (
    TrainOptions,
    dip_parts,
    fit_dip,
    fit_dog,
    train_dip,
    train_dog,
)

SPEC = FeatureSpec()


def planted(count: int, seed: int, groups: int = 20) -> Samples:
    """Pairs on de_dust2; half the attackers aim at their victim. The planted rule: a hit iff
    the victim is closer than 15 m and within 0.35 rad of the attacker's aim. A hit with the
    AWP does 85 HP, with the Glock-18 20 HP; it lands in the Head when the victim stands lower
    than the attacker, else in the Chest."""
    rng = np.random.default_rng(seed)
    attacker = np.column_stack([rng.uniform(-30, 25, count), rng.uniform(-10, 50, count)])
    step = rng.uniform(2, 30, count)
    heading = rng.uniform(-np.pi, np.pi, count)
    victim = attacker + step[:, None] * np.column_stack([np.cos(heading), np.sin(heading)])
    aim = np.where(rng.random(count) < 0.5, heading, rng.uniform(-np.pi, np.pi, count))
    aim += rng.normal(0, 0.2, count)
    z_a, z_v = rng.uniform(-1, 1, count), rng.uniform(-1, 1, count)
    bearing = np.angle(np.exp(1j * (heading - aim)))
    hit = (step < 15) & (np.abs(bearing) < 0.35)
    awp = rng.random(count) < 0.5
    damage = np.where(awp, 85.0, 20.0) + rng.normal(0, 3, count)
    head = z_v < z_a
    group = np.array([f"m r{g}" for g in rng.integers(0, groups, count)], dtype=object)
    return Samples(
        map_name=np.full(count, "de_dust2", dtype=object),
        attacker_position=np.column_stack([attacker, z_a]),
        victim_position=np.column_stack([victim, z_v]),
        attacker_yaw=np.degrees(aim) % 360,
        victim_yaw=rng.uniform(0, 360, count),
        attacker_hp=np.full(count, 100, np.int16),
        victim_hp=np.full(count, 100, np.int16),
        attacker_weapon=np.where(awp, "AWP", "Glock-18").astype(object),
        victim_armor=np.full(count, 100, np.int16),
        victim_helmet=np.ones(count, bool),
        hit=hit,
        damage=np.where(hit, np.clip(damage, 1, 100), 0).astype(np.float32),
        hp_lost=np.where(hit, np.clip(damage, 1, 100), 0).astype(np.float32),
        hit_group=np.where(hit, np.where(head, 0, 2), -1).astype(np.int8),
        group=group,
        match=np.full(count, "m", dtype=object),
        tick=np.arange(count, dtype=np.int64),
        mode=np.full(count, "frames", dtype=object),
    )


FAST = TrainOptions(epochs=25, batch_size=64, learning_rate=3e-3, patience=25, seed=0)


def test_dip_learns_the_planted_signal() -> None:
    train, test = planted(2000, seed=1), planted(1000, seed=2)
    val = planted(400, seed=3)
    trained = train_dip(train.features(SPEC), train.hit, val.features(SPEC), val.hit, FAST)
    probability = dip_probabilities(LoadedDip(trained.net, SPEC, 0.5), test)
    assert roc_auc(test.hit, probability) > 0.9  # chance is 0.5
    assert np.mean((probability >= 0.5) == test.hit) > 0.85  # always "miss" scores ~0.78


def test_dog_learns_the_planted_signal() -> None:
    train, val, test = (planted(3000, seed=s) for s in (4, 5, 6))
    train, val, test = (s.take(s.hit) for s in (train, val, test))
    trained = train_dog(
        train.features(SPEC),
        train.damage,
        train.hit_group,
        val.features(SPEC),
        val.damage,
        val.hit_group,
        TrainOptions(epochs=40, batch_size=32, learning_rate=3e-3, patience=40, seed=0),
    )
    result = evaluate_dog(LoadedDog(trained.net, SPEC), test, seed=0, draws=5, min_cell=5)
    draws = 5
    for weapon, expected in (("AWP", 85.0), ("Glock-18", 20.0)):
        generated = result.generated_damage[result.generated_weapon == weapon]
        assert abs(generated.mean() - expected) < 10, weapon  # the two means are 65 HP apart
    assert result.metrics["hit_group_accuracy_generated"] > 0.8  # the rule is in the condition
    assert result.metrics["damage_mae_hp"] < 15
    assert len(result.generated_damage) == draws * len(test)


def test_training_is_deterministic_and_leaves_global_rng_alone() -> None:
    data, val = planted(300, seed=7), planted(100, seed=8)
    options = TrainOptions(epochs=3, batch_size=32, seed=11)

    def weights(seed: int) -> dict[str, torch.Tensor]:
        options_seeded = TrainOptions(**{**options.__dict__, "seed": seed})
        return train_dip(
            data.features(SPEC), data.hit, val.features(SPEC), val.hit, options_seeded
        ).net.state_dict()

    torch.manual_seed(123)
    expected_next = torch.rand(3)
    torch.manual_seed(123)
    threads = torch.get_num_threads()
    one = weights(11)
    assert torch.equal(torch.rand(3), expected_next)
    assert torch.get_num_threads() == threads
    two, other = weights(11), weights(12)
    assert all(torch.equal(one[k], two[k]) for k in one)
    assert not all(torch.equal(one[k], other[k]) for k in one)


def test_dog_training_is_deterministic() -> None:
    data = planted(600, seed=9)
    data = data.take(data.hit)

    def run() -> dict[str, torch.Tensor]:
        f = data.features(SPEC)
        options = TrainOptions(epochs=2, batch_size=16, seed=3)
        trained = train_dog(f, data.damage, data.hit_group, f, data.damage, data.hit_group, options)
        return trained.net.state_dict()

    one, two = run(), run()
    assert all(torch.equal(one[k], two[k]) for k in one)


def test_best_epoch_is_kept_and_patience_stops() -> None:
    data, val = planted(400, seed=10), planted(200, seed=11)
    options = TrainOptions(epochs=40, batch_size=32, learning_rate=0.3, patience=2, seed=0)
    trained = train_dip(data.features(SPEC), data.hit, val.features(SPEC), val.hit, options)
    history = trained.history
    assert trained.stopped_early
    assert len(history) == trained.best_epoch + options.patience < options.epochs
    best = history[trained.best_epoch - 1]
    assert best.best and best.val_loss == min(r.val_loss for r in history)
    with torch.no_grad():
        logits = trained.net(*tensors(val.features(SPEC)))
        loss = F.binary_cross_entropy_with_logits(logits, torch.from_numpy(val.hit.astype("f4")))
    assert float(loss) == pytest.approx(best.val_loss, rel=1e-5)


def test_progress_reports_every_batch_and_epoch() -> None:
    data = planted(200, seed=12)
    seen = []
    options = TrainOptions(epochs=2, batch_size=64, patience=5)
    train_dip(data.features(SPEC), data.hit, data.features(SPEC), data.hit, options, seen.append)
    ends = [p for p in seen if p.record is not None]
    assert [p.epoch for p in ends] == [1, 2]
    assert len(seen) == 2 * (4 + 1)  # 200 samples: batches of 64, 64, 64, 8
    assert all(p.batches == 4 for p in seen)


def test_fit_dip_splits_by_group_and_chooses_a_threshold_on_validation() -> None:
    samples = planted(3000, seed=13, groups=30)
    split = split_samples(samples, "round", 0, 0.2, 0.2)
    run = fit_dip(samples, split, FAST, SPEC, balanced="eval")
    groups = {name: set(samples.group[index]) for name, index in run.parts.items()}
    assert not groups["train"] & groups["test"] and not groups["val"] & groups["test"]
    assert np.array_equal(run.parts["train"], split.part("train"))  # eval: train unbalanced
    assert samples.hit[run.parts["test"]].mean() == 0.5
    assert 0.0 < run.model.threshold < 1.0
    assert run.test.metrics["roc_auc"] > 0.9
    summary = run.summary()
    assert summary["samples"]["test"] == len(run.parts["test"])
    assert summary["test_metrics"]["threshold"] == run.model.threshold


def test_fit_dog_uses_damaging_samples_only() -> None:
    samples = planted(2000, seed=14, groups=20)
    split = split_samples(samples, "round", 0, 0.2, 0.2)
    options = TrainOptions(epochs=2, batch_size=32, seed=0)
    run = fit_dog(samples, split, options, SPEC, draws=2, min_cell=3)
    for index in run.parts.values():
        assert samples.hit[index].all()
    assert run.test.metrics["samples"] == len(run.parts["test"])


def test_dip_parts_balancing() -> None:
    samples = planted(1000, seed=15)
    split = split_samples(samples, "round", 0, 0.2, 0.2)
    every = dip_parts(samples, split, "all", 0)
    assert all(samples.hit[i].mean() == 0.5 for i in every.values())
    none = dip_parts(samples, split, "none", 0)
    assert all(np.array_equal(none[n], split.part(n)) for n in none)
    with pytest.raises(DecoyError, match="balance must be"):
        dip_parts(samples, split, "some", 0)


@pytest.mark.parametrize(
    "kwargs",
    [{"epochs": 0}, {"batch_size": 1}, {"learning_rate": 0.0}, {"patience": 0}, {"threads": 0}],
)
def test_bad_options(kwargs: dict[str, float]) -> None:
    with pytest.raises(DecoyError):
        TrainOptions(**kwargs)  # type: ignore[arg-type]


def test_too_few_samples() -> None:
    data = planted(50, seed=16)
    one = data.take(slice(0, 1))
    with pytest.raises(DecoyError, match="needs at least 2"):
        train_dip(one.features(SPEC), one.hit, data.features(SPEC), data.hit, FAST)
