"""Splitting samples into train, validation and test parts by match or by round, and the 1:1
balancing of DIP's positives and negatives.

A split never cuts a round (or, by match, a match) in two: samples of one step share their
round's game state, so a split by sample would leak the test part into training.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Literal, get_args

import numpy as np

from decoy_cli.errors import DecoyError
from decoy_cli.modeling.sample_set import Samples

SplitUnit = Literal["match", "round"]
"""What a split never cuts in two."""
SplitPart = Literal["all", "train", "val", "test"]
"""A part of a split to score on; "all" is every sample."""
SPLITS: tuple[SplitUnit, ...] = get_args(SplitUnit)
DEFAULT_SPLIT: SplitUnit = "match"
DEFAULT_SEED = 0
"""The seed of the split, the balancing and (training) the weights and shuffling."""
DEFAULT_VAL_FRACTION = 0.15
DEFAULT_TEST_FRACTION = 0.15


@dataclass(frozen=True)
class Split:
    """Sample indices of the train, validation and test parts, and the groups of each."""

    train: np.ndarray
    val: np.ndarray
    test: np.ndarray
    units: dict[str, list[str]]

    def part(self, name: SplitPart) -> np.ndarray:
        """The indices of "train", "val", "test" or "all" (every index, sorted)."""
        if name == "all":
            return np.sort(np.concatenate([self.train, self.val, self.test]))
        if name not in ("train", "val", "test"):
            raise DecoyError(f"subset must be all, train, val or test, not {name!r}")
        return getattr(self, name)


def split_samples(
    samples: Samples, by: SplitUnit, seed: int, val_fraction: float, test_fraction: float
) -> Split:
    """Split by match or by round (never by sample): the units, sorted, are shuffled with the
    seed; the first round(test_fraction * n) (at least 1) go to test, the next
    round(val_fraction * n) (at least 1) to validation, the rest to training."""
    if by not in SPLITS:
        raise DecoyError(f"split must be match or round, not {by!r}")
    for name, value in (("validation", val_fraction), ("test", test_fraction)):
        if not (0.0 < value < 1.0):
            raise DecoyError(f"the {name} fraction must be between 0 and 1, not {value}")
    if val_fraction + test_fraction >= 1.0:
        raise DecoyError("the validation and test fractions leave nothing to train on")
    unit_of = samples.match if by == "match" else samples.group
    units = sorted(set(unit_of.tolist()))
    n = len(units)
    n_test = max(1, round(test_fraction * n))
    n_val = max(1, round(val_fraction * n))
    if n - n_test - n_val < 1:
        what = "matches" if by == "match" else "rounds"
        hint = ": use --split round" if by == "match" else ""
        raise DecoyError(
            f"a split by {by} needs at least 3 {what} with samples, the data has {n}{hint}"
        )
    order = np.random.default_rng(seed).permutation(n)
    shuffled = [units[i] for i in order]
    parts = {
        "test": shuffled[:n_test],
        "val": shuffled[n_test : n_test + n_val],
        "train": shuffled[n_test + n_val :],
    }
    index = {
        name: np.flatnonzero(np.isin(unit_of, np.array(members, dtype=object)))
        for name, members in parts.items()
    }
    return Split(
        index["train"], index["val"], index["test"], {k: sorted(v) for k, v in parts.items()}
    )


FOLDS = 5
"""Folds of a leave-rounds-out evaluation."""


def deal_folds(
    units: Sequence[str], rng: np.random.Generator, folds: int = FOLDS
) -> dict[str, int]:
    """Deal the units (rounds), sorted then shuffled by `rng`, into `folds` folds in turn: each
    unit is a test unit of exactly one fold, never cut in two (module doc)."""
    ordered = np.array(sorted(set(units)), dtype=object)
    shuffled = rng.permutation(ordered)
    return {str(unit): k % folds for k, unit in enumerate(shuffled)}


def leave_matches_out(samples: Samples, rng: np.random.Generator) -> np.ndarray:
    """(K,) the test fold of every sample: each match of a map with several matches is a fold
    of its own (leave-one-match-out); the rounds of a map with one match are dealt into
    `FOLDS` folds of their own (`deal_folds`), as no other match of that map could stand in."""
    fold = np.zeros(len(samples), dtype=np.int64)
    next_fold = 0
    for name in sorted({str(m) for m in samples.map_name}):
        of_map = samples.map_name == name
        matches = sorted({str(m) for m in samples.match[of_map]})
        if len(matches) > 1:
            unit_of = {m: next_fold + k for k, m in enumerate(matches)}
            units = samples.match
        else:
            dealt = deal_folds([str(g) for g in samples.group[of_map]], rng)
            unit_of = {g: next_fold + k for g, k in dealt.items()}
            units = samples.group
        fold[of_map] = [unit_of[str(u)] for u in units[of_map]]
        next_fold = int(fold[of_map].max()) + 1
    return fold


def balance(samples: Samples, index: np.ndarray, seed: int) -> np.ndarray:
    """The indices in `index` with all positives and as many negatives, drawn with the seed (all
    negatives when there are fewer), sorted: the paper's 1:1 balanced DIP set."""
    index = np.asarray(index, dtype=np.int64)
    positive = index[samples.hit[index]]
    negative = index[~samples.hit[index]]
    if len(negative) > len(positive):
        negative = np.random.default_rng(seed).choice(negative, len(positive), replace=False)
    return np.sort(np.concatenate([positive, negative]))
