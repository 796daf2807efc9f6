"""Kill-level fidelity of full rounds (docs/metrics.md): who died when, by whose hand, who was up.

`kill_row` measures one round from its deaths (seconds, NaN: survived; the killer's row, -1:
none known; for the replay whether its fight caused the death) and the alive flags at the
data's frames, in the data and in the replay; its columns (`KILL_COLUMNS`) go into the round's
row. `kill_table` pools the rows of many rounds into the
metrics, each with a 95% interval by resampling whole rounds:

* `death_recall`: the share of real deaths the replay's fight reproduces, the same player
  killed (not scripted from the data) within `DEATH_WINDOW_S` of the real time;
* `killer_agreement`: of the real deaths with a known killer, the share the replay reproduces by
  the same killer;
* `first_death_side_agreement`, `first_death_player_agreement`: the round's first death, in
  rounds with a death in both;
* `alive_corr`, `alive_mad`: per round, the Pearson correlation and the mean absolute difference
  of the alive counts of both sides over the data's frames, averaged over rounds;
* `advantage_agreement`: per round, the share of frames where the same side has more players
  alive (or neither), averaged over rounds.
"""

from __future__ import annotations

import math

import numpy as np
import pandas as pd

from decoy_cli.metrics.bootstrap import Interval, RoundBootstrap

DEATH_WINDOW_S = 3.0
"""How close in time a replayed death must be to the real one to reproduce it."""

KILL_COLUMNS = (
    "deaths_original",
    "deaths_replay",
    "deaths_recalled",
    "killers_known",
    "killers_agree",
    "first_death_side_original",
    "first_death_side_replay",
    "first_death_player_original",
    "first_death_player_replay",
    "alive_corr",
    "alive_mad",
    "advantage_agreement",
)
"""Columns of a round's row that `kill_row` fills."""

Measured = tuple[float, int, str, Interval]
"""A metric's value, how many it is over, what those are, and its interval."""

KILL_METRICS = (
    "death_recall",
    "killer_agreement",
    "first_death_side_agreement",
    "first_death_player_agreement",
    "alive_corr",
    "alive_mad",
    "advantage_agreement",
)


def kill_row(
    names: list[str],
    sides: list[str],
    original: tuple[np.ndarray, np.ndarray],
    replay: tuple[np.ndarray, np.ndarray, np.ndarray],
    alive_original: np.ndarray,
    alive_replay: np.ndarray,
) -> dict[str, object]:
    """`KILL_COLUMNS` of one round; `original` is (death seconds, killer row) per player,
    `replay` the same and whether its fight caused the death; the alive flags (P, F) at the
    data's frames."""
    o_s, o_killer = (np.asarray(a) for a in original)
    r_s, r_killer, r_fight = (np.asarray(a) for a in replay)
    died = np.isfinite(o_s)
    with np.errstate(invalid="ignore"):
        close = np.abs(r_s - o_s) <= DEATH_WINDOW_S + 1e-9
    recalled = died & np.isfinite(r_s) & r_fight.astype(bool) & close
    known = died & (o_killer >= 0)
    row: dict[str, object] = {
        "deaths_original": int(died.sum()),
        "deaths_replay": int(np.isfinite(r_s).sum()),
        "deaths_recalled": int(recalled.sum()),
        "killers_known": int(known.sum()),
        "killers_agree": int((known & recalled & (r_killer == o_killer)).sum()),
    }
    for label, times in (("original", o_s), ("replay", r_s)):
        first = int(np.nanargmin(times)) if np.isfinite(times).any() else -1
        row[f"first_death_side_{label}"] = sides[first] if first >= 0 else None
        row[f"first_death_player_{label}"] = names[first] if first >= 0 else None
    side = np.asarray(sides)
    counts = [
        np.concatenate([alive[side == "T"].sum(axis=0), alive[side == "CT"].sum(axis=0)])
        for alive in (np.asarray(alive_original, bool), np.asarray(alive_replay, bool))
    ]
    o_c, r_c = (c.astype(np.float64) for c in counts)
    row["alive_corr"] = _pearson(o_c, r_c)
    row["alive_mad"] = float(np.mean(np.abs(o_c - r_c))) if len(o_c) else math.nan
    half = len(o_c) // 2
    lead_o = np.sign(o_c[:half] - o_c[half:])
    lead_r = np.sign(r_c[:half] - r_c[half:])
    row["advantage_agreement"] = float(np.mean(lead_o == lead_r)) if half else math.nan
    return row


def _pearson(x: np.ndarray, y: np.ndarray) -> float:
    if len(x) < 2 or np.ptp(x) == 0 or np.ptp(y) == 0:
        return math.nan
    return float(np.corrcoef(x, y)[0, 1])


def kill_table(rounds: pd.DataFrame, seed: int = 0) -> pd.DataFrame:
    """metric, value, n, note, low, high, interval_note: the module's metrics over the rounds
    that have the kill columns (rounds of a movement-only replay have them too)."""
    rows = rounds[rounds["deaths_original"].notna()] if len(rounds) else rounds
    boot = RoundBootstrap(len(rows), seed=seed)
    index = np.arange(len(rows))

    def column(name: str) -> np.ndarray:
        return pd.to_numeric(rows[name], errors="coerce").to_numpy(np.float64)

    def ratio(part: str, whole: str, what: str) -> Measured:
        top, bottom = column(part), column(whole)
        total = float(bottom.sum())
        value = float(top.sum()) / total if total else math.nan
        interval = boot.sums_interval(np.column_stack([top, bottom]), _ratio_of_sums)
        return value, int(total), what, interval

    def share(name: str, keep: np.ndarray, what: str) -> Measured:
        values = np.where(keep, column(name), np.nan) if len(rows) else np.zeros(0)
        finite = np.isfinite(values)
        value = float(values[finite].mean()) if finite.any() else math.nan
        return value, int(finite.sum()), what, boot.interval(values, index, "mean")

    both = rows["first_death_side_original"].notna() & rows["first_death_side_replay"].notna()
    both = both.to_numpy(bool) if len(rows) else np.zeros(0, bool)
    same_side = (rows["first_death_side_original"] == rows["first_death_side_replay"]).to_numpy()
    same_player = (
        rows["first_death_player_original"] == rows["first_death_player_replay"]
    ).to_numpy()
    window = f"real deaths (within {DEATH_WINDOW_S:g} s)"
    results = {
        "death_recall": ratio("deaths_recalled", "deaths_original", window),
        "killer_agreement": ratio("killers_agree", "killers_known", "real deaths, killer known"),
        "first_death_side_agreement": _flags(
            same_side, both, boot, index, "rounds, a death in both"
        ),
        "first_death_player_agreement": _flags(
            same_player, both, boot, index, "rounds, a death in both"
        ),
        "alive_corr": share("alive_corr", np.ones(len(rows), bool), "rounds (mean)"),
        "alive_mad": share("alive_mad", np.ones(len(rows), bool), "rounds (mean, players)"),
        "advantage_agreement": share(
            "advantage_agreement", np.ones(len(rows), bool), "rounds (mean share of frames)"
        ),
    }
    return pd.DataFrame(
        [
            {
                "metric": name,
                "value": value,
                "n": n,
                "note": note,
                "low": interval.low,
                "high": interval.high,
                "interval_note": interval.note,
            }
            for name, (value, n, note, interval) in results.items()
        ]
    )


def _flags(
    same: np.ndarray, keep: np.ndarray, boot: RoundBootstrap, index: np.ndarray, what: str
) -> Measured:
    values = np.where(keep, same.astype(np.float64), np.nan)
    value = float(np.nanmean(values)) if keep.any() else math.nan
    return value, int(keep.sum()), what, boot.interval(values, index, "mean")


def _ratio_of_sums(sums: np.ndarray) -> np.ndarray:
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.where(sums[:, 1] > 0, sums[:, 0] / sums[:, 1], np.nan)
