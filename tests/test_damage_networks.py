"""DIP and DOG networks (shapes, layers, determinism, loss) and the model-folder format."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
import torch
import torch.nn.functional as F
from trained_nets import trained_like

from decoy_cli.damage.features import PAPER_SPEC, Features, FeatureSpec
from decoy_cli.damage.model_folder import (
    FORMAT_VERSION,
    load_dip,
    load_dog,
    save_dip,
    save_dog,
)
from decoy_cli.damage.networks import DipNet, DogNet, DogOutput, tensors
from decoy_cli.errors import ModelError
from decoy_cli.modeling.losses import dog_loss
from decoy_cli.modeling.train_options import DogLossWeights


def random_features(k: int, seed: int = 0) -> Features:
    """K rows of plausible normalised features (one-hots where one-hots belong)."""
    rng = np.random.default_rng(seed)
    onehot = np.eye(8, dtype=np.float32)[np.full(k, 1)]
    weapon = np.eye(34, dtype=np.float32)[rng.integers(0, 34, k)]
    armor = rng.integers(0, 2, (k, 2)).astype(np.float32)
    return Features(onehot, rng.uniform(-1, 1, (k, 11)).astype(np.float32), weapon, armor)


def test_layers_are_the_papers() -> None:
    dip = {k: tuple(v.shape) for k, v in DipNet().state_dict().items()}
    assert dip["game_state_encoder.coords_embed.0.weight"] == (32, 11)
    assert dip["game_state_encoder.weapon_embed.0.weight"] == (32, 34)
    assert not any(k.startswith("game_state_encoder.map_embed.1") for k in dip)  # no BN in DIP
    assert dip["classifier.1.running_mean"] == (128,) and dip["classifier.4.weight"] == (1, 128)
    dog = {k: tuple(v.shape) for k, v in DogNet().state_dict().items()}
    assert dog["game_state_encoder.map_embed.1.running_var"] == (32,)
    assert dog["vae_encoder.encoder.0.weight"] == (256, 192)
    assert dog["vae_encoder.encoder.8.weight"] == (64, 128)
    assert dog["vae_encoder.mu_layer.weight"] == dog["vae_encoder.logvar_layer.weight"] == (8, 64)
    assert dog["vae_decoder.decoder.0.weight"] == (64, 136)
    assert dog["vae_decoder.decoder.8.weight"] == (256, 128)
    assert dog["vae_decoder.damage_regressor.0.weight"] == (1, 256)
    assert dog["vae_decoder.hit_group_classifier.weight"] == (6, 256)
    assert sum(p.numel() for p in DipNet().parameters()) == 18_785
    assert sum(p.numel() for p in DogNet().parameters()) == 147_863


def test_shapes_in_training_and_eval() -> None:
    features = random_features(7)
    inputs = tensors(features)
    dip = DipNet()
    assert dip(*inputs).shape == (7,)
    dog = DogNet()
    damage = torch.rand(7, 1)
    onehot = F.one_hot(torch.arange(7) % 6, 6).float()
    out = dog(damage, onehot, *inputs)
    assert isinstance(out, DogOutput)
    assert out.damage.shape == (7, 1) and out.hit_logits.shape == (7, 6)
    assert out.mu.shape == out.logvar.shape == (7, 8)
    dip.eval()
    dog.eval()
    one = tensors(features.take(slice(0, 1)))  # eval mode takes a single row
    assert dip(*one).shape == (1,)
    hp, logits = dog.generate(*one, generator=torch.Generator().manual_seed(0))
    assert hp.shape == (1,) and logits.shape == (1, 6)


def test_generation_is_deterministic_under_a_seed() -> None:
    dog = trained_like(DogNet(), 1)
    inputs = tensors(random_features(20))
    with torch.inference_mode():
        first = dog.generate(*inputs, generator=torch.Generator().manual_seed(5))
        again = dog.generate(*inputs, generator=torch.Generator().manual_seed(5))
        other = dog.generate(*inputs, generator=torch.Generator().manual_seed(6))
    assert torch.equal(first[0], again[0]) and torch.equal(first[1], again[1])
    assert not torch.equal(first[0], other[0])
    # z is the generator's first draw: decoding that z by hand gives the same outcome
    z = torch.randn((20, 8), generator=torch.Generator().manual_seed(5))
    with torch.inference_mode():
        damage, logits = dog.vae_decoder(z, dog.game_state_encoder(*inputs))
    torch.testing.assert_close(first[0], 100 * damage.squeeze(1))
    torch.testing.assert_close(first[1], logits)
    # reconstruction mode: eps from the given generator
    damage = torch.rand((20, 1), generator=torch.Generator().manual_seed(9))
    onehot = torch.eye(6)[torch.arange(20) % 6]
    with torch.inference_mode():
        runs = [
            dog(damage, onehot, *inputs, generator=torch.Generator().manual_seed(s))
            for s in (2, 2, 3)
        ]
    torch.testing.assert_close(runs[0].damage, runs[1].damage, rtol=0, atol=0)
    torch.testing.assert_close(runs[0].mu, runs[2].mu, rtol=0, atol=0)  # mu needs no noise
    assert not torch.equal(runs[0].damage, runs[2].damage)


def test_dog_loss_terms() -> None:
    k = 4
    logits = torch.tensor([[3.0, 0, 0, 0, 0, 0]] * k)
    output = DogOutput(
        damage=torch.full((k, 1), 0.5),
        hit_logits=logits,
        mu=torch.zeros(k, 8),
        logvar=torch.zeros(k, 8),
    )
    target = torch.full((k, 1), 0.3)
    groups = torch.tensor([0, 0, 2, 5])
    total, parts = dog_loss(output, target, groups, DogLossWeights())
    ce = F.cross_entropy(logits, groups).item()
    assert parts["damage"] == pytest.approx(0.04)
    assert parts["hit_group"] == pytest.approx(ce)
    assert parts["kl"] == pytest.approx(0.0)
    assert parts["total"] == pytest.approx(total.item()) == pytest.approx(0.04 + 0.7 * ce)
    # KL of N(1, e) against N(0, 1) per latent dimension: 0.5 * (e + 1 - 1 - 1)
    shifted = DogOutput(output.damage, logits, torch.ones(k, 8), torch.ones(k, 8))
    _, parts = dog_loss(shifted, target, groups, DogLossWeights(damage=0, hit_group=0, kl=1))
    assert parts["kl"] == pytest.approx(8 * 0.5 * (np.e - 1)) == pytest.approx(parts["total"])


def test_dog_loss_trains() -> None:
    torch.manual_seed(0)
    dog = DogNet()
    features = random_features(64, seed=3)
    inputs = tensors(features)
    damage = torch.from_numpy(features.coords[:, :1].copy()).abs()  # a planted signal
    groups = torch.from_numpy((features.coords[:, 1] > 0).astype(np.int64) * 2)
    onehot = F.one_hot(groups, 6).float()
    optimiser = torch.optim.Adam(dog.parameters(), lr=3e-3)
    losses = []
    for _ in range(60):
        optimiser.zero_grad()
        total, parts = dog_loss(dog(damage, onehot, *inputs), damage, groups, DogLossWeights())
        total.backward()
        optimiser.step()
        losses.append(parts["total"])
    assert np.mean(losses[-5:]) < 0.5 * np.mean(losses[:5])


def test_tensors_are_float32_views() -> None:
    features = random_features(3)
    blocks = tensors(features)
    assert [tuple(b.shape) for b in blocks] == [(3, 8), (3, 11), (3, 34), (3, 2)]
    assert all(b.dtype == torch.float32 for b in blocks)


# ---- the model folder -------------------------------------------------------------------------


def test_model_folder_round_trip(tmp_path: Path) -> None:
    dip = trained_like(DipNet(), 1)
    dog = trained_like(DogNet(), 2)
    spec = FeatureSpec(centre_m=(1.0, 2.0, 3.0))
    assert save_dip(tmp_path / "m", dip, spec, 0.37, {"data": "test", "n": 3}) == tmp_path / "m"
    save_dog(tmp_path / "m", dog, PAPER_SPEC, {"note": "x"})
    assert sorted(p.name for p in (tmp_path / "m").iterdir()) == [
        "dip.json",
        "dip.pt",
        "dog.json",
        "dog.pt",
    ]
    loaded_dip = load_dip(tmp_path / "m")
    loaded_dog = load_dog(tmp_path / "m")
    assert loaded_dip.spec == spec and loaded_dip.threshold == 0.37
    assert loaded_dip.metadata == {"data": "test", "n": 3}
    assert loaded_dog.spec == PAPER_SPEC and loaded_dog.metadata == {"note": "x"}
    assert not loaded_dip.net.training and not loaded_dog.net.training
    for net, loaded in ((dip, loaded_dip.net), (dog, loaded_dog.net)):
        for key, value in net.state_dict().items():
            assert torch.equal(value, loaded.state_dict()[key]), key
    inputs = tensors(random_features(9))
    with torch.inference_mode():
        torch.testing.assert_close(dip(*inputs), loaded_dip.net(*inputs), rtol=0, atol=0)
    description = json.loads((tmp_path / "m" / "dip.json").read_text())
    assert description["format_version"] == FORMAT_VERSION and description["kind"] == "dip"
    assert description["parameters"] == 18_785


def _folder(tmp_path: Path) -> Path:
    folder = tmp_path / "models"
    save_dip(folder, DipNet(), FeatureSpec(), 0.5)
    save_dog(folder, DogNet(), FeatureSpec())
    return folder


def _edit_json(path: Path, **changes: object) -> None:
    data = json.loads(path.read_text())
    data.update(changes)
    path.write_text(json.dumps(data))


@pytest.mark.parametrize(
    ("damage", "message"),
    [
        ("no-folder", "no such model folder"),
        ("no-json", "no dip.json (a model folder holds dip.pt and dip.json)"),
        ("no-weights", "dip.pt: no such file"),
        ("bad-json", "not readable JSON (Expecting value, line 1)"),
        ("foreign-json", "not a decoy damage-model description"),
        ("version", "format version 99, this decoy reads version 1"),
        ("kind", "describes a 'dog' model, not dip"),
        ("vocabulary", "made for other map, weapon or hit-group one-hot orders"),
        ("threshold", "threshold must be a number in [0, 1]"),
        ("spec", "unknown feature units 'inches'"),
        ("text-weights", "dip.pt: not a torch weights file"),
        ("no-state-dict", "dip.pt: holds no state dict of named tensors"),
        (
            "dog-weights",
            "weights do not fit a DipNet: 9 missing (first classifier.0.weight); 84 unexpected",
        ),
        ("shapes", "classifier.4.weight has shape (2, 128), a DipNet needs (1, 128)"),
        ("nan", "weights hold NaN or infinite values"),
    ],
)
def test_bad_model_folders_are_one_model_error(tmp_path: Path, damage: str, message: str) -> None:
    folder = _folder(tmp_path)
    description, weights = folder / "dip.json", folder / "dip.pt"
    state = DipNet().state_dict()
    match damage:
        case "no-folder":
            folder = tmp_path / "nothing"
        case "no-json":
            description.unlink()
        case "no-weights":
            weights.unlink()
        case "bad-json":
            description.write_text("")
        case "foreign-json":
            description.write_text('{"hello": 1}')
        case "version":
            _edit_json(description, format_version=99)
        case "kind":
            _edit_json(description, kind="dog")
        case "vocabulary":
            data = json.loads(description.read_text())
            data["vocabulary"]["weapons"] = data["vocabulary"]["weapons"][::-1]
            description.write_text(json.dumps(data))
        case "threshold":
            _edit_json(description, threshold=1.5)
        case "spec":
            _edit_json(description, features={"units": "inches"})
        case "text-weights":
            weights.write_text("these are not weights")
        case "no-state-dict":
            torch.save([1, 2, 3], weights)
        case "dog-weights":
            torch.save(DogNet().state_dict(), weights)
        case "shapes":
            state["classifier.4.weight"] = torch.zeros(2, 128)
            torch.save(state, weights)
        case "nan":
            state["classifier.4.bias"] = torch.tensor([float("nan")])
            torch.save(state, weights)
    with pytest.raises(ModelError) as error:
        load_dip(folder)
    assert message in str(error.value)
    assert "\n" not in str(error.value)


def test_dip_and_dog_folders_load_separately(tmp_path: Path) -> None:
    save_dog(tmp_path, DogNet(), FeatureSpec())
    assert load_dog(tmp_path).spec == FeatureSpec()
    with pytest.raises(ModelError, match=r"no dip\.json"):
        load_dip(tmp_path)
    with pytest.raises(ValueError, match="threshold is a probability"):
        save_dip(tmp_path, DipNet(), FeatureSpec(), 1.2)
