"""Training samples for DIP and DOG from ESTA rounds, built as the paper builds them.

A sample is one ordered (attacker, victim) pair of enemies at one 0.5 s step: the state of both
players (as a `CombatBatch` row, the input of `decoy_cli.damage.features.encode`), whether the
attacker damaged the victim in that step (DIP's label) and, for a damaging pair, how much and
where (DOG's targets). Every sample carries its group, "MATCH rROUND", so that a split never puts
one round (or, by match, one match) on both sides; see `split_samples`.

The pieces, one job each:

* sample_set.py: the `Samples` container (batching, model inputs) and `SampleStats`;
* damage_rows.py: which damage rows count, the damage value and hit group of a pair and step;
* frames_mode.py: the paper's mode, for rounds with the frames of both teams;
* events_mode.py: the events-only proxy, for files without frames;
* split.py: the split by match or round and DIP's 1:1 balancing.

This module reads the rounds through the project's one round loop (`decoy_cli.esta.batch`): a
file that cannot be read, a broken round and a round whose samples fail to build each become a
`RoundFailure` in `SampleStats.failures`, and the rest of the data is still used. The mode is
chosen per round ("auto": frames of both teams present -> frames, else events).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Literal, get_args

from decoy_cli.errors import DecoyError
from decoy_cli.esta import Round, RoundFailure, collect_match_files, each_round, iter_rounds
from decoy_cli.modeling.events_mode import event_samples
from decoy_cli.modeling.frames_mode import frame_samples, has_both_teams
from decoy_cli.modeling.sample_set import MAX_DAMAGE_HP, Samples, SampleStats
from decoy_cli.modeling.split import (
    DEFAULT_SPLIT,
    DEFAULT_TEST_FRACTION,
    DEFAULT_VAL_FRACTION,
    SPLITS,
    Split,
    balance,
    split_samples,
)

SampleMode = Literal["auto", "frames", "events"]
"""How rounds become samples (`build_samples`)."""
MODES: tuple[SampleMode, ...] = get_args(SampleMode)
DEFAULT_MODE: SampleMode = "auto"

DEFAULT_WINDOW_S = 2.0
"""Events-only mode: how far (seconds) an event row places a player, and how long an attacker
must have dealt its victim no damage for the pair to be a negative."""

SAMPLE_ERROR = "sample error"
"""The `RoundFailure.kind` of a round whose samples could not be built."""

_FAILURES_SHOWN = 3


def build_samples(
    data: Sequence[str | Path],
    mode: SampleMode = DEFAULT_MODE,
    window_s: float = DEFAULT_WINDOW_S,
    on_file: Callable[[Path, int, int], None] | None = None,
) -> tuple[Samples, SampleStats]:
    """Samples from ESTA match files or folders of them (module docstring).

    `on_file(path, done, total)` is called after each file. Unreadable files and broken rounds
    are recorded in `SampleStats.failures` and the others are used. No usable sample at all
    (also when every file failed) is a DecoyError, so is a missing input.
    """
    if mode not in MODES:
        raise DecoyError(f"mode must be one of {', '.join(MODES)}, not {mode!r}")
    if not (math.isfinite(window_s) and window_s > 0):
        raise DecoyError(f"the event window must be a positive number of seconds, not {window_s}")
    files, _ = collect_match_files(data)
    if not files:
        raise DecoyError("no data given: pass ESTA match files or folders")
    stats = SampleStats(files=len(files))
    parts: list[Samples] = []

    def counted(round_: Round) -> tuple[Samples | None, SampleStats]:
        counts = SampleStats()
        return round_samples(round_, mode, window_s, counts), counts

    for done, path in enumerate(files, start=1):
        for item in each_round(iter_rounds([path]), counted, SAMPLE_ERROR):
            if isinstance(item, RoundFailure):  # counts of a failed round are left out
                stats.failures.append(item)
                continue
            _, (part, counts) = item
            stats.merge(counts)
            if part is None or len(part) == 0:
                stats.rounds_without_samples += 1
            else:
                parts.append(part)
        if on_file is not None:
            on_file(path, done, len(files))
    samples = Samples.concat(parts)
    stats.positives = int(samples.hit.sum())
    stats.negatives = len(samples) - stats.positives
    if len(samples) == 0:
        raise DecoyError(_no_samples_message(data, stats))
    return samples, stats


def _no_samples_message(data: Sequence[str | Path], stats: SampleStats) -> str:
    """One line: what was read and, when inputs failed, how many and the first reasons."""
    names = ", ".join(str(d) for d in data)
    line = (
        f"{names}: no usable samples ({stats.files} files; rounds need frames of both teams or "
        "firearm damage events between enemies)"
    )
    if stats.failures:
        shown = "; ".join(f.message for f in stats.failures[:_FAILURES_SHOWN])
        more = len(stats.failures) - _FAILURES_SHOWN
        inputs = "input" if len(stats.failures) == 1 else "inputs"
        line += f"; {len(stats.failures)} {inputs} failed: {shown}" + (
            f" (and {more} more)" if more > 0 else ""
        )
    return line


def round_samples(round_: Round, mode: str, window_s: float, stats: SampleStats) -> Samples | None:
    """The samples of one round in the given mode ("auto" picks per round); None when the mode
    cannot read it (forced frames without both teams' frames)."""
    use_frames = has_both_teams(round_) if mode == "auto" else mode == "frames"
    if use_frames:
        if not has_both_teams(round_):
            return None
        stats.rounds_frames += 1
        return frame_samples(round_, stats)
    stats.rounds_events += 1
    return event_samples(round_, window_s, stats)


__all__ = [
    "DEFAULT_MODE",
    "DEFAULT_SPLIT",
    "DEFAULT_TEST_FRACTION",
    "DEFAULT_VAL_FRACTION",
    "DEFAULT_WINDOW_S",
    "MAX_DAMAGE_HP",
    "MODES",
    "SAMPLE_ERROR",
    "SPLITS",
    "SampleStats",
    "Samples",
    "Split",
    "balance",
    "build_samples",
    "has_both_teams",
    "round_samples",
    "split_samples",
]
