"""What a damage model was trained or scored on: the choice of data and split, the provenance
kept in a trained model's metadata, and strict JSON writing of both.

One `SampleChoice` reads and splits the samples for training and for `decoy models evaluate`,
so the same choice gives the same train, validation and test parts in both.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from decoy_cli import __version__, files
from decoy_cli.files import JsonObject, object_at
from decoy_cli.modeling.sample_set import Samples, SampleStats
from decoy_cli.modeling.samples import DEFAULT_MODE, DEFAULT_WINDOW_S, SampleMode, build_samples
from decoy_cli.modeling.split import (
    DEFAULT_SEED,
    DEFAULT_SPLIT,
    DEFAULT_TEST_FRACTION,
    DEFAULT_VAL_FRACTION,
    Split,
    SplitUnit,
    split_samples,
)
from decoy_cli.modeling.train_options import TrainOptions

FileCallback = Callable[[Path, int, int], None]
"""Called after each data file is read: (path, files done, files in all)."""


@dataclass(frozen=True, kw_only=True)
class SampleChoice:
    """Which ESTA files, how their rounds become samples (`mode`, `window_s`) and how the
    samples are split (by match or round, with `seed`)."""

    data: Sequence[Path]
    mode: SampleMode = DEFAULT_MODE
    window_s: float = DEFAULT_WINDOW_S
    split_by: SplitUnit = DEFAULT_SPLIT
    seed: int = DEFAULT_SEED
    val_fraction: float = DEFAULT_VAL_FRACTION
    test_fraction: float = DEFAULT_TEST_FRACTION

    def read(self, on_file: FileCallback | None = None) -> tuple[Samples, SampleStats]:
        """The samples of the data, and what reading them counted and left out."""
        return build_samples(self.data, self.mode, self.window_s, on_file=on_file)

    def split(self, samples: Samples) -> Split:
        """The samples' train, validation and test parts."""
        return split_samples(
            samples, self.split_by, self.seed, self.val_fraction, self.test_fraction
        )


def provenance(
    *,
    command: str,
    choice: SampleChoice,
    split: Split,
    stats: SampleStats,
    options: TrainOptions,
    samples: Samples,
) -> dict[str, object]:
    """What a model was trained on and how (`command` is "dip" or "dog"; "maps", those of its
    training samples): kept in the model's JSON metadata, so a model folder says where it came
    from."""
    return {
        "trained_with": f"decoy {__version__}: decoy train {command}",
        "data": [str(d) for d in choice.data],
        "maps": sorted({str(m) for m in samples.map_name[split.train]}),
        "mode": choice.mode,
        "window_s": choice.window_s,
        "split": {
            "by": choice.split_by,
            "seed": choice.seed,
            "val_fraction": choice.val_fraction,
            "test_fraction": choice.test_fraction,
            "units": split.units,
        },
        "sample_stats": stats.to_json(),
        "options": options.to_json(),
    }


def seen_in(metadata: JsonObject, samples: Samples, parts: Sequence[str]) -> np.ndarray | None:
    """(K,) True for the samples of the matches or rounds a model's metadata (`provenance`)
    records in `parts` of its split ("train", "val", "test"); None when it records no split by
    match or round (an imported or older model): what it saw is not known."""
    split = object_at(metadata, "split")
    units = split.get("units")
    if split.get("by") not in ("match", "round") or not isinstance(units, dict):
        return None
    seen = [str(u) for part in parts for u in _listed(units.get(part))]
    unit_of = samples.match if split["by"] == "match" else samples.group
    return np.isin(unit_of.astype(str), seen)


def _listed(value: object) -> list[object]:
    return value if isinstance(value, list) else []


def write_json(path: Path, data: dict[str, object]) -> None:
    """Pretty strict JSON in the order given (`decoy_cli.files.write_json`)."""
    files.write_json(path, data, sort_keys=False)
