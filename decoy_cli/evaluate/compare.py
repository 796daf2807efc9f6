"""A paired comparison of two `decoy evaluate` runs: is run B's replay closer to reality than A's?

`read_run` reads a run's output folder (`players.csv`, `rounds.csv`, `tables/places.csv`);
`compare_runs` pairs the player-rounds both runs evaluated, after checking that the paired
rounds were read from the same content (`file_sha`), and gives per trajectory metric:

* the mean paired difference B − A (lower is better: every trajectory metric is a distance)
  with its 95% bootstrap interval, resampling whole rounds (`decoy_cli.metrics.bootstrap`);
* the share of player-rounds B improved (B < A) and made worse (B > A);
* the two-sided Wilcoxon signed-rank p-value of the differences (scipy; zero differences
  dropped, NaN when every difference is zero);

and by nav place the change of the mean distance between replay and player. Anything that stops
the pairing is a `CompareError` with one line.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pandas as pd

from decoy_cli.errors import CompareError
from decoy_cli.evaluate.intervals import round_codes
from decoy_cli.evaluate.run_tables import read_run_table
from decoy_cli.metrics import ALL_METRIC_NAMES, METRIC_NAMES
from decoy_cli.metrics.bootstrap import RoundBootstrap

KEY = ["match", "round", "player"]

COMPARE_COLUMNS = (
    "metric",
    "pairs",
    "mean_a",
    "mean_b",
    "mean_difference",
    "low",
    "high",
    "improved_share",
    "worse_share",
    "wilcoxon_p",
    "note",
)
"""Columns of the comparison table (compare.csv), one row per metric."""


@dataclass(frozen=True)
class Run:
    """The tables of one evaluation run."""

    folder: Path
    players: pd.DataFrame
    rounds: pd.DataFrame
    places: pd.DataFrame | None
    metrics: tuple[str, ...]
    """The trajectory metrics its players.csv has."""


@dataclass(frozen=True)
class Comparison:
    """The paired comparison of run B against run A (module docstring)."""

    a: Run
    b: Run
    table: pd.DataFrame
    """`COMPARE_COLUMNS`."""
    differences: pd.DataFrame
    """One row per paired player-round: match, round, player, side and B − A of each metric."""
    places: pd.DataFrame
    """place, mean_error_a_m, mean_error_b_m, difference_m (by |difference|, largest first)."""
    rounds: int
    only_a: int
    """Evaluated player-rounds of A that B did not evaluate (and the reverse)."""
    only_b: int
    dropped: tuple[str, ...] = ()
    """Optional metrics only one run computed (`paper_dtw_fastdtw`), left out of the pairing."""


def _csv(path: Path) -> pd.DataFrame:
    """A table of a run, checked (`run_tables.read_run_table`), or a CompareError saying why
    it cannot be read."""
    if not path.exists():
        raise CompareError(f"{path}: not found (is {path.parent} a `decoy evaluate` output?)")
    return read_run_table(path, CompareError)


def read_run(folder: Path) -> Run:
    """Read a `decoy evaluate` output folder; a missing, truncated or foreign table raises."""
    folder = Path(folder)
    if not folder.is_dir():
        raise CompareError(f"{folder}: no such folder")
    players = _csv(folder / "players.csv")
    rounds = _csv(folder / "rounds.csv")
    for name, frame, needed in (
        ("players.csv", players, [*KEY, "side", "reason"]),
        ("rounds.csv", rounds, ["match", "round", "file_sha"]),
    ):
        missing = [c for c in needed if c not in frame.columns]
        if missing:
            raise CompareError(f"{folder / name}: lacks the columns {', '.join(missing)}")
    metrics = tuple(m for m in ALL_METRIC_NAMES if m in players.columns)
    if not metrics:
        raise CompareError(f"{folder / 'players.csv'}: no trajectory metric column")
    evaluated = players["reason"].isna()
    values = players.loc[evaluated, list(metrics)].apply(pd.to_numeric, errors="coerce")
    broken = ~np.isfinite(values.to_numpy(np.float64)).all(axis=1)
    if broken.any():
        row = int(np.flatnonzero(broken)[0])
        raise CompareError(
            f"{folder / 'players.csv'}: {int(broken.sum())} evaluated rows lack metric values "
            f"(the first at data row {row + 1}): a truncated or edited file"
        )
    places_file = folder / "tables" / "places.csv"
    places = _csv(places_file) if places_file.exists() else None
    return Run(folder, players, rounds, places, metrics)


def compare_runs(a: Run, b: Run, *, seed: int = 0) -> Comparison:
    """Pair the player-rounds both runs evaluated and compare them (module docstring)."""
    only = set(a.metrics) ^ set(b.metrics)
    if only & set(METRIC_NAMES):  # an optional metric (paper_dtw_fastdtw) may be missing
        raise CompareError(
            f"{a.folder} and {b.folder} have different metric sets (only one has "
            f"{', '.join(sorted(only))}): runs of different versions cannot be paired"
        )
    shas = a.rounds[["match", "round", "file_sha"]].merge(
        b.rounds[["match", "round", "file_sha"]], on=["match", "round"], suffixes=("_a", "_b")
    )
    differ = shas[shas["file_sha_a"] != shas["file_sha_b"]]
    if len(differ):
        first = differ.iloc[0]
        raise CompareError(
            f"{a.folder} and {b.folder} read different data for {len(differ)} rounds (round "
            f"{first['round']} of {first['match']} first): only runs of the same files pair"
        )
    metrics = [m for m in a.metrics if m in b.metrics]  # an optional metric one run lacks: out
    left = a.players[a.players["reason"].isna()][[*KEY, "side", *metrics]]
    right = b.players[b.players["reason"].isna()][[*KEY, *metrics]]
    pairs = left.merge(right, on=KEY, suffixes=("_a", "_b"))
    if not len(pairs):
        raise CompareError(
            f"{a.folder} and {b.folder} have no evaluated player-round in common: nothing to pair"
        )
    codes, rounds = round_codes(pairs)
    boot = RoundBootstrap(rounds, seed=seed)
    differences = pairs[[*KEY, "side"]].copy()
    rows = []
    for metric in metrics:
        va = pairs[f"{metric}_a"].to_numpy(np.float64)
        vb = pairs[f"{metric}_b"].to_numpy(np.float64)
        d = np.round(vb - va, 9)  # float noise below a nanometre is no difference
        differences[metric] = d
        interval = boot.interval(d, codes, "mean")
        p, why = _wilcoxon(d)
        rows.append(
            {
                "metric": metric,
                "pairs": len(d),
                "mean_a": float(va.mean()),
                "mean_b": float(vb.mean()),
                "mean_difference": float(d.mean()),
                "low": interval.low,
                "high": interval.high,
                "improved_share": float(np.mean(d < 0)),
                "worse_share": float(np.mean(d > 0)),
                "wilcoxon_p": p,
                "note": "; ".join(n for n in (interval.note, why) if n),
            }
        )
    return Comparison(
        a=a,
        b=b,
        table=pd.DataFrame(rows, columns=list(COMPARE_COLUMNS)),
        differences=differences,
        places=_places(a, b),
        rounds=rounds,
        only_a=len(left) - len(pairs),
        only_b=len(right) - len(pairs),
        dropped=tuple(sorted(only)),
    )


def _wilcoxon(d: np.ndarray) -> tuple[float, str]:
    """Two-sided Wilcoxon signed-rank p-value of paired differences, or NaN and why not."""
    from scipy.stats import wilcoxon

    if not np.any(d != 0):
        return float("nan"), "every difference is zero"
    return float(wilcoxon(d[d != 0]).pvalue), ""


def _places(a: Run, b: Run) -> pd.DataFrame:
    """Mean distance replay-player by nav place in both runs, largest change first."""
    columns = ["place", "mean_error_a_m", "mean_error_b_m", "difference_m"]
    if a.places is None or b.places is None:
        return pd.DataFrame(columns=columns)
    for run in (a, b):
        assert run.places is not None
        if not {"place", "mean_error_m"} <= set(run.places.columns):
            raise CompareError(f"{run.folder / 'tables' / 'places.csv'}: not a places table")
    merged = a.places[["place", "mean_error_m"]].merge(
        b.places[["place", "mean_error_m"]], on="place", suffixes=("_a", "_b")
    )
    merged.columns = columns[:3]
    merged["difference_m"] = merged["mean_error_b_m"] - merged["mean_error_a_m"]
    order = merged["difference_m"].abs().sort_values(ascending=False, na_position="last").index
    return merged.loc[order].reset_index(drop=True)
