"""Import of the paper's checkpoints: outputs against an independent functional forward pass of
the raw state dict, the hit-group permutation, `decoy models import-decoy`, and bad input.

Runs on a synthetic checkpoint folder in the paper's format (always) and on the published
checkpoints in ../shared/data/decoy_checkpoints (skipped when absent).
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
import torch
import torch.nn.functional as F
from typer.testing import CliRunner

from decoy_cli.cli import app
from decoy_cli.csgo import HAMMER_TO_M
from decoy_cli.damage.features import HIT_GROUPS, PAPER_SPEC, encode
from decoy_cli.damage.model_folder import load_dip, load_dog
from decoy_cli.damage.networks import DipNet, DogNet, tensors
from decoy_cli.errors import ModelError
from decoy_cli.modeling.paper_import import (
    HIT_GROUP_PERMUTATION,
    PAPER_HIT_GROUPS,
    import_paper,
    permute_hit_groups,
)
from decoy_cli.sim.combat import CombatBatch

DATA = Path(__file__).resolve().parents[1].parent / "shared" / "data"
PUBLISHED = DATA / "decoy_checkpoints"
runner = CliRunner()
WIDE = {"COLUMNS": "200"}


def random_state(net: torch.nn.Module, seed: int) -> dict[str, torch.Tensor]:
    """The net's state dict with random weights and BatchNorm statistics."""
    generator = torch.Generator().manual_seed(seed)
    state = {}
    for name, tensor in net.state_dict().items():
        if name.endswith("running_var"):
            state[name] = torch.rand(tensor.shape, generator=generator) + 0.5
        elif tensor.is_floating_point():
            state[name] = torch.randn(tensor.shape, generator=generator) * 0.3
        else:
            state[name] = tensor.clone()
    return state


def write_paper_folder(folder: Path, dip_state: dict, dog_state: dict) -> Path:
    """A checkpoint folder laid out as the paper's files are (training checkpoint dicts)."""
    folder.mkdir(parents=True, exist_ok=True)
    for kind, state, epoch in (("dip", dip_state, 3), ("dog", dog_state, 16)):
        checkpoint = {
            "epoch": epoch,
            "model_state_dict": state,
            "optimizer_state_dict": {"state": {}, "param_groups": []},
            "best_val_loss": 0.25,
        }
        torch.save(checkpoint, folder / f"{kind}_best_model.pth")
    (folder / "dip_args.json").write_text(json.dumps({"hidden_dim": 256, "use_batchnorm": True}))
    (folder / "dog_args.json").write_text(json.dumps({"hidden_dim": 256, "latent_dim": 8}))
    return folder


@pytest.fixture(scope="module")
def synthetic(tmp_path_factory: pytest.TempPathFactory) -> Path:
    folder = tmp_path_factory.mktemp("paper") / "checkpoints"
    return write_paper_folder(folder, random_state(DipNet(), 1), random_state(DogNet(), 2))


@pytest.fixture(params=["synthetic", "published"])
def checkpoints(request: pytest.FixtureRequest, synthetic: Path) -> Path:
    if request.param == "synthetic":
        return synthetic
    if not (PUBLISHED / "dip_best_model.pth").is_file():
        pytest.skip(f"the paper's published checkpoints are not at {PUBLISHED}")
    return PUBLISHED


# ---- an independent forward pass over the raw state dict (eval mode) --------------------------


def _linear(state: dict, name: str, x: torch.Tensor) -> torch.Tensor:
    return F.linear(x, state[f"{name}.weight"], state[f"{name}.bias"])


def _norm(state: dict, name: str, x: torch.Tensor) -> torch.Tensor:
    return F.batch_norm(
        x,
        state[f"{name}.running_mean"],
        state[f"{name}.running_var"],
        state[f"{name}.weight"],
        state[f"{name}.bias"],
        training=False,
        eps=1e-5,
    )


def _condition(state: dict, batchnorm: bool, inputs: tuple) -> torch.Tensor:
    parts = []
    for branch, x in zip(("map", "coords", "weapon", "armor"), inputs, strict=True):
        h = _linear(state, f"game_state_encoder.{branch}_embed.0", x)
        if batchnorm:
            h = _norm(state, f"game_state_encoder.{branch}_embed.1", h)
        parts.append(F.relu(h))
    return torch.cat(parts, dim=1)


def functional_dip(state: dict, inputs: tuple) -> torch.Tensor:
    h = _condition(state, False, inputs)
    h = F.relu(_norm(state, "classifier.1", _linear(state, "classifier.0", h)))
    return _linear(state, "classifier.4", h).squeeze(1)


def _blocks(state: dict, prefix: str, h: torch.Tensor) -> torch.Tensor:
    for layer in (0, 4, 8):
        h = F.relu(_norm(state, f"{prefix}.{layer + 1}", _linear(state, f"{prefix}.{layer}", h)))
    return h


def functional_decode(state: dict, z: torch.Tensor, inputs: tuple) -> tuple:
    h = _blocks(state, "vae_decoder.decoder", torch.cat([z, _condition(state, True, inputs)], 1))
    damage = _linear(state, "vae_decoder.damage_regressor.0", h)
    return damage.squeeze(1), _linear(state, "vae_decoder.hit_group_classifier", h)


def functional_encode(state: dict, damage: torch.Tensor, paper_onehot: torch.Tensor, inputs):
    embed = [
        F.relu(_norm(state, f"vae_encoder.{name}.1", _linear(state, f"vae_encoder.{name}.0", x)))
        for name, x in (("damage_value_embed", damage), ("hit_group_embed", paper_onehot))
    ]
    h = _blocks(
        state, "vae_encoder.encoder", torch.cat([*embed, _condition(state, True, inputs)], 1)
    )
    return _linear(state, "vae_encoder.mu_layer", h), _linear(state, "vae_encoder.logvar_layer", h)


def hand_built_batch() -> CombatBatch:
    """Five de_dust2 duels in Hammer units: long range rifles, an AWP, pistols up close, a
    victim behind the attacker, one above."""
    attacker_u = [(-400, 1600, 0), (1300, 2900, 130), (-1700, 800, 0), (200, 200, 0), (0, 0, 0)]
    victim_u = [(-400, 2600, 30), (-300, 2500, 0), (-1650, 900, 0), (-300, 200, 0), (50, 0, 300)]
    a = np.array(attacker_u, float) * HAMMER_TO_M
    v = np.array(victim_u, float) * HAMMER_TO_M
    return CombatBatch(
        attacker=np.arange(5),
        victim=np.arange(5) + 5,
        attacker_position=a,
        victim_position=v,
        attacker_yaw=np.array([90.0, 190.0, 60.0, 0.0, 0.0]),
        victim_yaw=np.array([270.0, 10.0, 240.0, 90.0, 180.0]),
        attacker_hp=np.array([100, 74, 12, 100, 55], np.int16),
        victim_hp=np.full(5, 100, np.int16),
        attacker_weapon=np.array(["AK-47", "AWP", "Glock-18", "USP-S", "M4A1"], dtype=object),
        victim_armor=np.array([100, 0, 100, 50, 0], np.int16),
        victim_helmet=np.array([True, False, False, True, False]),
        map_name="de_dust2",
    )


def raw_state(path: Path) -> dict[str, torch.Tensor]:
    return torch.load(path, map_location="cpu", weights_only=True)["model_state_dict"]


def test_imported_models_equal_a_functional_forward(checkpoints: Path, tmp_path: Path) -> None:
    result = import_paper(checkpoints, tmp_path / "out")
    assert result.folder == tmp_path / "out" and result.threshold == 0.444
    assert [m.kind for m in result.models] == ["dip", "dog"]
    dip, dog = load_dip(tmp_path / "out"), load_dog(tmp_path / "out")
    assert dip.spec == dog.spec == PAPER_SPEC and dip.threshold == 0.444
    assert dip.metadata["checkpoint"] == "dip_best_model.pth" and dip.metadata["epoch"] == 3
    assert "permuted" in dog.metadata["note"]

    inputs = tensors(encode(hand_built_batch(), PAPER_SPEC))
    dip_state = raw_state(checkpoints / "dip_best_model.pth")
    dog_state = raw_state(checkpoints / "dog_best_model.pth")
    with torch.inference_mode():
        torch.testing.assert_close(dip.net(*inputs), functional_dip(dip_state, inputs))

        hp, logits = dog.net.generate(*inputs, generator=torch.Generator().manual_seed(11))
        z = torch.randn((5, 8), generator=torch.Generator().manual_seed(11))
        damage, paper_logits = functional_decode(dog_state, z, inputs)
        torch.testing.assert_close(hp, 100 * damage)
        # project group j is the paper's group of the same name
        for j, name in enumerate(HIT_GROUPS):
            torch.testing.assert_close(logits[:, j], paper_logits[:, PAPER_HIT_GROUPS.index(name)])

        groups = torch.tensor([0, 2, 3, 4, 5])  # Head, Chest, Stomach, Arm, Leg (project codes)
        paper_groups = torch.tensor([PAPER_HIT_GROUPS.index(HIT_GROUPS[g]) for g in groups])
        damage_in = torch.tensor([[0.27], [1.0], [0.5], [0.12], [0.2]])
        out = dog.net(damage_in, F.one_hot(groups, 6).float(), *inputs)
        mu, logvar = functional_encode(
            dog_state, damage_in, F.one_hot(paper_groups, 6).float(), inputs
        )
        torch.testing.assert_close(out.mu, mu)
        torch.testing.assert_close(out.logvar, logvar)


def test_published_models_give_plausible_outcomes() -> None:
    if not (PUBLISHED / "dip_best_model.pth").is_file():
        pytest.skip(f"the paper's published checkpoints are not at {PUBLISHED}")
    from decoy_cli.modeling.paper_import import import_dip, import_dog

    dip, _ = import_dip(PUBLISHED / "dip_best_model.pth")
    dog, _ = import_dog(PUBLISHED / "dog_best_model.pth")
    inputs = tensors(encode(hand_built_batch(), PAPER_SPEC))
    with torch.inference_mode():
        probability = torch.sigmoid(dip(*inputs))
        hp, logits = dog.generate(
            *(t.repeat(200, 1) for t in inputs), generator=torch.Generator().manual_seed(0)
        )
    assert torch.all((probability > 0) & (probability < 1))
    assert probability.max() - probability.min() > 0.05  # the inputs matter
    assert 5 < float(hp.median()) < 150  # generated damage is in HP, not HP / 100
    share = torch.bincount(logits.argmax(1), minlength=6).float() / len(logits)
    # in CS:GO most damage lands on the chest and stomach, a neck hit is rare
    assert share[HIT_GROUPS.index("Neck")] < 0.1
    assert share[HIT_GROUPS.index("Chest")] + share[HIT_GROUPS.index("Stomach")] > 0.3


def test_the_hit_group_permutation_goes_by_name() -> None:
    assert PAPER_HIT_GROUPS == ("Head", "Neck", "Stomach", "Chest", "Arm", "Leg")
    assert HIT_GROUP_PERMUTATION == (0, 1, 3, 2, 4, 5)
    state = random_state(DogNet(), 4)
    permuted = permute_hit_groups(state)
    classifier = "vae_decoder.hit_group_classifier"
    embed = "vae_encoder.hit_group_embed.0.weight"
    for j, name in enumerate(HIT_GROUPS):
        k = PAPER_HIT_GROUPS.index(name)
        assert torch.equal(permuted[f"{classifier}.weight"][j], state[f"{classifier}.weight"][k])
        assert permuted[f"{classifier}.bias"][j] == state[f"{classifier}.bias"][k]
        assert torch.equal(permuted[embed][:, j], state[embed][:, k])
    untouched = [k for k in state if k not in (embed, f"{classifier}.weight", f"{classifier}.bias")]
    assert all(permuted[k] is state[k] for k in untouched)


def test_import_decoy_command(synthetic: Path, tmp_path: Path) -> None:
    out = tmp_path / "paper"
    result = runner.invoke(
        app, ["models", "import-decoy", str(synthetic), "--out", str(out)], env=WIDE
    )
    assert result.exit_code == 0, result.output
    for text in ("imported DECOY checkpoints", "dip_best_model.pth", "18,785", "147,863"):
        assert text in result.stdout
    assert f"--models {out}" in result.stdout
    assert sorted(p.name for p in out.iterdir()) == ["dip.json", "dip.pt", "dog.json", "dog.pt"]


def _bad_folder(tmp_path: Path, damage: str) -> Path:
    folder = write_paper_folder(
        tmp_path / "src", random_state(DipNet(), 1), random_state(DogNet(), 2)
    )
    match damage:
        case "file":
            return folder / "dip_best_model.pth"
        case "no-dog":
            (folder / "dog_best_model.pth").unlink()
        case "text":
            (folder / "dip_best_model.pth").write_text("<html>not found</html>")
        case "swapped":
            (folder / "dip_best_model.pth").write_bytes(
                (folder / "dog_best_model.pth").read_bytes()
            )
        case "shapes":
            state = random_state(DipNet(), 1)
            state["game_state_encoder.weapon_embed.0.weight"] = torch.zeros(32, 33)
            torch.save({"model_state_dict": state}, folder / "dip_best_model.pth")
        case "args":
            (folder / "dog_args.json").write_text(json.dumps({"latent_dim": 16}))
        case "bad-args":
            (folder / "dip_args.json").write_text("{")
    return folder


@pytest.mark.parametrize(
    ("damage", "message"),
    [
        ("missing", "{folder}: not a folder (expected one holding dip_best_model.pth and "),
        ("file", "{folder}: not a folder"),
        ("no-dog", "{folder}: no dog_best_model.pth"),
        ("text", "{folder}/dip_best_model.pth: not a torch weights file ("),
        ("swapped", "{folder}/dip_best_model.pth: weights do not fit a DipNet"),
        (
            "shapes",
            "{folder}/dip_best_model.pth: game_state_encoder.weapon_embed.0.weight has shape "
            "(32, 33), a DipNet needs (32, 34)",
        ),
        ("args", "{folder}/dog_args.json: latent_dim = 16; decoy imports the published"),
        ("bad-args", "{folder}/dip_args.json: not readable JSON"),
    ],
)
def test_bad_checkpoints_are_one_error_line(tmp_path: Path, damage: str, message: str) -> None:
    folder = tmp_path / "absent" if damage == "missing" else _bad_folder(tmp_path, damage)
    with pytest.raises(ModelError) as error:
        import_paper(folder, tmp_path / "out")
    assert str(error.value).startswith(message.format(folder=folder))
    result = runner.invoke(
        app, ["models", "import-decoy", str(folder), "--out", str(tmp_path / "o")]
    )
    assert result.exit_code == 1
    assert result.stderr == f"error: {error.value}\n"
    assert not (tmp_path / "o").exists()
