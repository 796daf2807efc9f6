"""The project's saved damage-model format: a folder with `dip.pt` + `dip.json` and/or
`dog.pt` + `dog.json`.

The `.pt` file is the network's state dict (`torch.save`; loaded with `weights_only=True`, so a
model folder cannot run code). The `.json` file says what the weights mean:

    {"format": "decoy-damage-model", "format_version": 1, "kind": "dip" | "dog",
     "weights": "dip.pt", "features": FeatureSpec.to_json(),
     "vocabulary": {"maps": [...], "weapons": [...], "hit_groups": [...]},
     "threshold": 0.444 (DIP only), "parameters": 18785, "metadata": {...free...}}

The vocabulary is stored so that a folder written with other one-hot orders is refused rather
than silently misread. Every problem with a folder (missing, corrupt, another format version,
another vocabulary, a state dict that does not fit the network) is one ModelError line. Files
are written atomically, the weights before the JSON that describes them.
"""

from __future__ import annotations

import io
import math
from dataclasses import dataclass, field
from pathlib import Path

import torch
from torch import nn

from decoy_cli.damage.calibration import CALIBRATION_FILE, Calibration
from decoy_cli.damage.features import HIT_GROUPS, MAPS, WEAPONS, FeatureSpec
from decoy_cli.damage.networks import DipNet, DogNet
from decoy_cli.errors import ModelError
from decoy_cli.files import JsonObject, json_text, object_at, write_atomic
from decoy_cli.reading import load_json, open_regular

FORMAT = "decoy-damage-model"
FORMAT_VERSION = 1
KINDS = ("dip", "dog")


@dataclass
class LoadedDip:
    """A DIP network in eval mode, its features, decision threshold and metadata."""

    net: DipNet
    spec: FeatureSpec
    threshold: float
    metadata: JsonObject = field(default_factory=dict)
    calibration: Calibration | None = None
    """The folder's `dip_calibration.json` (`decoy models calibrate`, `fight-threshold`), when
    it has one."""

    @property
    def decision_threshold(self) -> float:
        """The threshold on DIP's own probability the combat step decides by: an operating point
        set without rescaling (kind "none", `decoy models fight-threshold`), else DIP's own
        (Platt and temperature scaling keep the order and carry it over)."""
        calibration = self.calibration
        if calibration is not None and calibration.kind == "none":
            return calibration.threshold
        return self.threshold


@dataclass
class LoadedDog:
    """A DOG network in eval mode, its features and metadata."""

    net: DogNet
    spec: FeatureSpec
    metadata: JsonObject = field(default_factory=dict)


def vocabulary() -> JsonObject:
    """The one-hot orders the networks are built for."""
    return {"maps": list(MAPS), "weapons": list(WEAPONS), "hit_groups": list(HIT_GROUPS)}


def save_dip(
    folder: str | Path,
    net: DipNet,
    spec: FeatureSpec,
    threshold: float,
    metadata: JsonObject | None = None,
) -> Path:
    """Write `dip.pt` and `dip.json` into `folder` (created if needed); returns the folder. A
    `dip_calibration.json` there was fitted for the DIP this one replaces: it is removed."""
    threshold = float(threshold)
    if not 0.0 <= threshold <= 1.0:
        raise ValueError(f"a DIP threshold is a probability, got {threshold}")
    saved = _save(Path(folder), "dip", net, spec, {"threshold": threshold}, metadata or {})
    (saved / CALIBRATION_FILE).unlink(missing_ok=True)
    return saved


def save_dog(
    folder: str | Path, net: DogNet, spec: FeatureSpec, metadata: JsonObject | None = None
) -> Path:
    """Write `dog.pt` and `dog.json` into `folder` (created if needed); returns the folder."""
    return _save(Path(folder), "dog", net, spec, {}, metadata or {})


def _save(
    folder: Path,
    kind: str,
    net: nn.Module,
    spec: FeatureSpec,
    extra: JsonObject,
    metadata: JsonObject,
) -> Path:
    description: JsonObject = {
        "format": FORMAT,
        "format_version": FORMAT_VERSION,
        "kind": kind,
        "weights": f"{kind}.pt",
        "features": spec.to_json(),
        "vocabulary": vocabulary(),
        **extra,
        "parameters": sum(p.numel() for p in net.parameters()),
        "metadata": metadata,
    }
    text = json_text(description, sort_keys=False)  # before writing: unserialisable metadata
    buffer = io.BytesIO()
    torch.save({k: v.detach().cpu().clone() for k, v in net.state_dict().items()}, buffer)
    write_atomic(folder / f"{kind}.pt", buffer.getvalue())
    write_atomic(folder / f"{kind}.json", text.encode())
    return folder


def load_dip(folder: str | Path) -> LoadedDip:
    """The DIP of a model folder, in eval mode; a ModelError when it is missing or unusable."""
    description, state = _load(Path(folder), "dip")
    threshold = description.get("threshold")
    if (
        isinstance(threshold, bool)
        or not isinstance(threshold, int | float)
        or not (math.isfinite(threshold) and 0.0 <= threshold <= 1.0)
    ):
        raise ModelError(f"{Path(folder) / 'dip.json'}: threshold must be a number in [0, 1]")
    net = DipNet()
    load_state(net, state, Path(folder) / "dip.pt")
    return LoadedDip(
        net,
        FeatureSpec.from_json(description["features"]),
        float(threshold),
        object_at(description, "metadata"),
        load_calibration(Path(folder)),
    )


def load_calibration(folder: Path) -> Calibration | None:
    """The folder's DIP calibration, None without one; an unreadable one is a ModelError."""
    path = folder / CALIBRATION_FILE
    if not path.exists():
        return None
    data = load_json(path, ModelError)
    try:
        return Calibration.from_dict(data)
    except ValueError as error:
        raise ModelError(f"{path}: not a DIP calibration ({error})") from None


def save_calibration(folder: Path, calibration: Calibration) -> Path:
    """Write the DIP calibration into the model folder."""
    path = Path(folder) / CALIBRATION_FILE
    write_atomic(path, calibration.to_json().encode())
    return path


def load_dog(folder: str | Path) -> LoadedDog:
    """The DOG of a model folder, in eval mode; a ModelError when it is missing or unusable."""
    description, state = _load(Path(folder), "dog")
    net = DogNet()
    load_state(net, state, Path(folder) / "dog.pt")
    metadata = object_at(description, "metadata")
    return LoadedDog(net, FeatureSpec.from_json(description["features"]), metadata)


def _load(folder: Path, kind: str) -> tuple[JsonObject, dict[str, torch.Tensor]]:
    """The checked JSON description and the state dict of one model of a folder."""
    if not folder.is_dir():
        raise ModelError(f"{folder}: no such model folder")
    path = folder / f"{kind}.json"
    if not path.exists():
        raise ModelError(
            f"{folder}: no {kind}.json (a model folder holds {kind}.pt and {kind}.json)"
        )
    description = load_json(path, ModelError)
    if not isinstance(description, dict) or description.get("format") != FORMAT:
        raise ModelError(f"{path}: not a decoy damage-model description")
    if description.get("format_version") != FORMAT_VERSION:
        raise ModelError(
            f"{path}: format version {description.get('format_version')!r}, "
            f"this decoy reads version {FORMAT_VERSION}"
        )
    if description.get("kind") != kind:
        raise ModelError(f"{path}: describes a {description.get('kind')!r} model, not {kind}")
    if description.get("vocabulary") != vocabulary():
        raise ModelError(f"{path}: made for other map, weapon or hit-group one-hot orders")
    if not isinstance(description.get("metadata", {}), dict):
        raise ModelError(f"{path}: metadata must be an object")
    description.setdefault("metadata", {})
    if "features" not in description:
        raise ModelError(f"{path}: no feature spec")
    FeatureSpec.from_json(description["features"])
    weights = folder / f"{kind}.pt"
    return description, state_dict_of(read_torch_file(weights), weights)


def read_torch_file(path: Path) -> object:
    """What a torch.save file holds, loaded on the CPU with `weights_only=True` (no code runs);
    a missing, foreign or damaged file is one ModelError line."""
    if not path.exists():
        raise ModelError(f"{path}: no such file")
    try:
        with open_regular(path, ModelError) as handle:  # a FIFO is refused, not waited on
            return torch.load(handle, map_location="cpu", weights_only=True)
    except ModelError:
        raise
    except Exception as error:  # torch raises many kinds for foreign or damaged files
        text = str(error).strip()
        first = text.splitlines()[0] if text else type(error).__name__
        raise ModelError(f"{path}: not a torch weights file ({first[:160]})") from None


def state_dict_of(data: object, path: Path) -> dict[str, torch.Tensor]:
    """The state dict in what `read_torch_file` returned: a dict of named tensors, or a
    checkpoint dict holding one under "model_state_dict" (as the paper's files do)."""
    if isinstance(data, dict) and isinstance(data.get("model_state_dict"), dict):
        data = data["model_state_dict"]
    if not (
        isinstance(data, dict)
        and data
        and all(isinstance(k, str) and isinstance(v, torch.Tensor) for k, v in data.items())
    ):
        raise ModelError(f"{path}: holds no state dict of named tensors")
    return data


def load_state(net: nn.Module, state: dict[str, torch.Tensor], source: Path) -> None:
    """Load `state` into `net` (all keys, exact shapes) and put it in eval mode; a mismatch is
    one ModelError line naming the first offending layer."""
    expected = net.state_dict()
    missing = [k for k in expected if k not in state]
    unexpected = [k for k in state if k not in expected]
    if missing or unexpected:
        parts = []
        if missing:
            parts.append(f"{len(missing)} missing (first {missing[0]})")
        if unexpected:
            parts.append(f"{len(unexpected)} unexpected (first {unexpected[0]})")
        raise ModelError(
            f"{source}: weights do not fit a {type(net).__name__}: {'; '.join(parts)} tensors"
        )
    for key, tensor in expected.items():
        if tuple(state[key].shape) != tuple(tensor.shape):
            raise ModelError(
                f"{source}: {key} has shape {tuple(state[key].shape)}, "
                f"a {type(net).__name__} needs {tuple(tensor.shape)}"
            )
        if not state[key].dtype.is_floating_point and tensor.dtype.is_floating_point:
            raise ModelError(f"{source}: {key} is {state[key].dtype}, not floating point")
    net.load_state_dict(state, strict=True)
    if not all(torch.isfinite(v).all() for v in net.state_dict().values() if v.is_floating_point()):
        raise ModelError(f"{source}: weights hold NaN or infinite values")
    net.eval()
