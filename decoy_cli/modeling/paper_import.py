"""Import of the DECOY paper's published DIP and DOG checkpoints into the project's networks.

The paper's authors published their trained models in HATS-ICT/decoy (MIT):
`models/train-di_*/checkpoints/best_model.pth` (DIP) and `models/train-vae_*/.../best_model.pth`
(DOG), each with an `args.json`. `import_paper` reads them from one folder under the names
`dip_best_model.pth`, `dog_best_model.pth`, `dip_args.json` and `dog_args.json` (the args are
optional and, when present, checked), and writes a project model folder
(decoy_cli/damage/model_folder.py) that `decoy replay --models FOLDER` and the environment use.

What the import does to the weights:

* nothing to the layers: networks.py builds DIP and DOG with the paper's layer names and shapes,
  and every tensor must be present with its exact shape;
* the hit groups: the paper orders them Head, Neck, Stomach, Chest, Arm, Leg and the project
  Head, Neck, Chest, Stomach, Arm, Leg (decoy_cli.sim.combat.HIT_GROUPS), so the columns of
  DOG's hit-group embedding (`vae_encoder.hit_group_embed.0.weight`) and the rows of its
  hit-group classifier (`vae_decoder.hit_group_classifier.weight` and `.bias`) are permuted:
  project group j takes the paper's row or column of the same name. The imported DOG then
  reads and writes hit groups in the project's order, with the paper's behaviour unchanged.

Features: the paper's raw Hammer-unit features (`FeatureSpec(units="hammer")`); DIP threshold
0.444, the paper's.
"""

from __future__ import annotations

import hashlib
from dataclasses import dataclass, replace
from pathlib import Path

import torch

from decoy_cli.damage.features import HIT_GROUPS, MAPS, PAPER_SPEC
from decoy_cli.damage.model_folder import (
    load_state,
    read_torch_file,
    save_dip,
    save_dog,
    state_dict_of,
)
from decoy_cli.damage.networks import DipNet, DogNet
from decoy_cli.errors import ModelError
from decoy_cli.files import JsonObject
from decoy_cli.reading import load_json

PAPER_HIT_GROUPS = ("Head", "Neck", "Stomach", "Chest", "Arm", "Leg")
"""The hit-group order of the paper's DOG."""

HIT_GROUP_PERMUTATION = tuple(PAPER_HIT_GROUPS.index(group) for group in HIT_GROUPS)
"""Project hit group j is the paper's group HIT_GROUP_PERMUTATION[j]."""

PAPER_THRESHOLD = 0.444
"""The DIP decision threshold the paper reports."""

DIP_FILE = "dip_best_model.pth"
DOG_FILE = "dog_best_model.pth"
DIP_ARGS = "dip_args.json"
DOG_ARGS = "dog_args.json"

SOURCE = (
    "DECOY paper (Wang, Ustun, McGroarty, WSC 2025), published checkpoints of HATS-ICT/decoy "
    "(MIT license)"
)

_EXPECTED_ARGS = {
    "dip": {"hidden_dim": 256, "use_batchnorm": True},
    "dog": {"hidden_dim": 256, "latent_dim": 8, "use_batchnorm": True},
}
"""Training options the networks of networks.py reproduce; other values mean other layers."""


@dataclass(frozen=True)
class ImportedModel:
    """What was imported from one checkpoint file."""

    kind: str  # "dip" or "dog"
    source: Path
    sha256: str
    epoch: int | None
    best_val_loss: float | None
    parameters: int  # trainable parameters of the network


@dataclass(frozen=True)
class PaperImport:
    """The written model folder and the two imported checkpoints."""

    folder: Path
    models: tuple[ImportedModel, ImportedModel]
    threshold: float


def permute_hit_groups(state: dict[str, torch.Tensor]) -> dict[str, torch.Tensor]:
    """A copy of a paper DOG state dict with its hit groups in the project's order."""
    order = torch.tensor(HIT_GROUP_PERMUTATION)
    out = dict(state)
    embed = "vae_encoder.hit_group_embed.0.weight"
    out[embed] = state[embed][:, order].clone()
    for key in ("vae_decoder.hit_group_classifier.weight", "vae_decoder.hit_group_classifier.bias"):
        out[key] = state[key][order].clone()
    return out


def import_dip(path: Path) -> tuple[DipNet, ImportedModel]:
    """The paper's DIP checkpoint as a DipNet in eval mode."""
    net = DipNet()
    info, state = _read_checkpoint(Path(path), "dip")
    load_state(net, state, Path(path))
    return net, replace(info, parameters=sum(p.numel() for p in net.parameters()))


def import_dog(path: Path) -> tuple[DogNet, ImportedModel]:
    """The paper's DOG checkpoint as a DogNet in eval mode, hit groups in the project's order."""
    net = DogNet()
    info, state = _read_checkpoint(Path(path), "dog")
    load_state(net, state, Path(path))  # checks names and shapes before the permutation
    load_state(net, permute_hit_groups(state), Path(path))
    return net, replace(info, parameters=sum(p.numel() for p in net.parameters()))


def _read_checkpoint(path: Path, kind: str) -> tuple[ImportedModel, dict[str, torch.Tensor]]:
    data = read_torch_file(path)
    state = state_dict_of(data, path)
    extra = data if isinstance(data, dict) and "model_state_dict" in data else {}
    epoch = extra.get("epoch")
    loss = extra.get("best_val_loss")
    info = ImportedModel(
        kind=kind,
        source=path,
        sha256=hashlib.sha256(path.read_bytes()).hexdigest(),
        epoch=int(epoch) if isinstance(epoch, int) else None,
        best_val_loss=float(loss) if isinstance(loss, int | float) else None,
        parameters=0,  # set once the weights are loaded into a network
    )
    return info, state


def read_args(path: Path, kind: str) -> JsonObject | None:
    """The training options of a checkpoint (None without the file); a ModelError when they
    name another architecture than the one imported."""
    if not path.exists():
        return None
    args = load_json(path, ModelError)
    if not isinstance(args, dict):
        raise ModelError(f"{path}: args must be a JSON object")
    for key, wanted in _EXPECTED_ARGS[kind].items():
        if key in args and args[key] != wanted:
            raise ModelError(
                f"{path}: {key} = {args[key]!r}; decoy imports the published architecture "
                f"({key} = {wanted!r})"
            )
    return args


def import_paper(source: Path, out: Path) -> PaperImport:
    """Import `dip_best_model.pth` and `dog_best_model.pth` of the folder `source` (with their
    args JSON when present) and write them as a model folder `out`."""
    source = Path(source)
    if not source.is_dir():
        raise ModelError(f"{source}: not a folder (expected one holding {DIP_FILE} and {DOG_FILE})")
    missing = [name for name in (DIP_FILE, DOG_FILE) if not (source / name).is_file()]
    if missing:
        raise ModelError(f"{source}: no {' and no '.join(missing)}")
    dip_args = read_args(source / DIP_ARGS, "dip")
    dog_args = read_args(source / DOG_ARGS, "dog")
    dip, dip_info = import_dip(source / DIP_FILE)
    dog, dog_info = import_dog(source / DOG_FILE)
    save_dip(out, dip, PAPER_SPEC, PAPER_THRESHOLD, _metadata(dip_info, dip_args))
    save_dog(out, dog, PAPER_SPEC, _metadata(dog_info, dog_args))
    return PaperImport(Path(out), (dip_info, dog_info), PAPER_THRESHOLD)


def _metadata(info: ImportedModel, args: JsonObject | None) -> JsonObject:
    notes = {
        "dip": f"threshold {PAPER_THRESHOLD} as reported in the paper",
        "dog": "hit groups permuted from the paper's order "
        f"({', '.join(PAPER_HIT_GROUPS)}) to the project's ({', '.join(HIT_GROUPS)})",
    }
    return {
        "source": SOURCE,
        "checkpoint": info.source.name,
        "sha256": info.sha256,
        "epoch": info.epoch,
        "best_val_loss": info.best_val_loss,
        "training_args": args,
        "maps": list(MAPS),  # the paper's models were trained on ESTA data of all eight
        "note": notes[info.kind],
    }
