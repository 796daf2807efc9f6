"""Aggregate round records into the evaluation's tables, next to the DECOY paper's numbers.

`Accumulator` takes `RoundRecord`s in any order: table rows are kept by round and sorted at the
end, heat, place and HP data are integer sums, so the tables are identical whichever worker
finished which round first. `build_tables` then computes:

* `trajectory`: the ten trajectory metrics (both protocols, docs/metrics.md) by side and
  overall (mean, std, median, p90, and 95% bootstrap intervals of the mean and median that
  resample whole rounds), with the paper's Table 2 mean and std beside the paper protocol's
  metrics;
* `combat`: `hp_corr`, `paper_hp_corr`, `hp_rmse` from the exact integer HP sums (the same
  values `decoy_cli.metrics.hp_metrics` gives on the pooled player-frames), `death_time_corr`,
  `death_time_mae_s` and `outcome_agreement`, `end_reason_agreement`, with the paper's values;
* `bomb`: plant and defuse agreement, time, site and position errors (`metrics.bomb`);
* the death confusion counts, the outcome confusion matrices, HP over time (mean ± std on the
  fixed time grid), and by nav place how much time the players and the replay spend there and
  how far the replay is from the player there.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
import pandas as pd

from decoy_cli.evaluate.heat import read_grid_sums
from decoy_cli.evaluate.intervals import combat_intervals, trajectory_intervals
from decoy_cli.evaluate.record import PLAYER_COLUMNS, ROUND_COLUMNS, RoundRecord
from decoy_cli.evaluate.settings import EvalSettings
from decoy_cli.metrics import (
    ALL_METRIC_NAMES,
    FASTDTW_METRIC,
    GROUPS,
    METRIC_NAMES_CLOCK,
    BombMetrics,
    DeathTimeMetrics,
    MetricSummary,
    OutcomeMetrics,
    bomb_metrics,
    death_time_metrics,
    metric_names,
    outcome_metrics,
    pearson,
    summarize,
)
from decoy_cli.metrics.kills import kill_table

PAPER_TABLE2: dict[str, dict[str, tuple[float, float]]] = {
    "T": {
        "paper_euclidean": (0.420, 0.237),
        "paper_rmse": (5.155, 2.911),
        "paper_dtw": (0.873, 1.868),
        "paper_frechet_2d": (4.030, 8.599),
    },
    "CT": {
        "paper_euclidean": (0.467, 0.252),
        "paper_rmse": (5.720, 3.091),
        "paper_dtw": (1.332, 2.263),
        "paper_frechet_2d": (6.690, 9.910),
    },
    "all": {
        "paper_euclidean": (0.443, 0.246),
        "paper_rmse": (5.437, 3.016),
        "paper_dtw": (1.103, 2.088),
        "paper_frechet_2d": (5.360, 9.372),
    },
}
"""The DECOY paper's Table 2 (mean, std) by side, movement only (docs/metrics.md)."""

PAPER_VALUE_OF = {FASTDTW_METRIC: "paper_dtw"}
"""The paper's DTW was computed with FastDTW: it sits beside both `paper_dtw` (exact) and
`paper_dtw_fastdtw`."""

PAPER_COMBAT = {
    "paper_hp_corr": 0.961,
    "hp_rmse": 2.35,
    "death_time_corr": 0.809,
    "death_time_mae_s": 12.8,
    "outcome_agreement": 0.910,
}
"""The paper's combat and outcome fidelity (its HP correlation is of the mean HP curves)."""

COMBAT_METRICS = (
    "hp_corr",
    "paper_hp_corr",
    "hp_rmse",
    "death_time_corr",
    "death_time_mae_s",
    "outcome_agreement",
    "end_reason_agreement",
)

UNDECIDED = "undecided"
"""The replay's winner label when the simulation did not end the round before the data did."""
END_OF_DATA = "end of data"
NOT_RECORDED = "not recorded"


@dataclass
class Accumulator:
    """Round records summed up as they arrive (see the module docstring)."""

    settings: EvalSettings
    place_names: list[str]
    """Labels of the per-place counts (decoy_cli.evaluate.job.place_names)."""
    _rows: dict[tuple[str, int, str], tuple[dict, list[dict]]] = field(default_factory=dict)
    _hp_rounds: dict[tuple[str, int, str], list[int]] = field(default_factory=dict)
    heat_original: np.ndarray = field(init=False)
    heat_replay: np.ndarray = field(init=False)
    heat_off_graph: np.ndarray = field(init=False)
    """Original samples with no waypoint on their floor per grid cell."""
    error_count: np.ndarray = field(init=False)
    """Samples alive in both per grid cell of the original position."""
    error_mm: np.ndarray = field(init=False)
    """Their summed distance original-replay (mm)."""
    places_original: np.ndarray = field(init=False)
    places_off_graph: np.ndarray = field(init=False)
    places_replay: np.ndarray = field(init=False)
    places_error_count: np.ndarray = field(init=False)
    places_error_mm: np.ndarray = field(init=False)
    hp_pooled: list[int] = field(default_factory=lambda: [0] * 7)
    hp_frames: np.ndarray = field(default_factory=lambda: np.zeros((3, 0), np.int64))
    hp_bins: np.ndarray = field(init=False)

    def __post_init__(self) -> None:
        grid = self.settings.grid
        for name in ("heat_original", "heat_replay", "heat_off_graph", "error_count", "error_mm"):
            setattr(self, name, np.zeros((grid.ny, grid.nx), np.int64))
        for name in ("original", "off_graph", "replay", "error_count", "error_mm"):
            setattr(self, f"places_{name}", np.zeros(len(self.place_names), np.int64))
        self.hp_bins = np.zeros((5, self.settings.hp_bins), np.int64)

    @property
    def rounds(self) -> int:
        return len(self._rows)

    def add(self, record: RoundRecord, file: str) -> None:
        """Add one round's record, read from `file` (adding a round twice is an error)."""
        key = (record.match_id, record.round_num, record.file_sha)
        if key in self._rows:
            raise ValueError(f"round {record.round_num} of {record.match_id} added twice")
        row = {**record.round, "file": file, "file_sha": record.file_sha}
        self._rows[key] = (row, record.players)
        self._hp_rounds[key] = list(record.hp.pooled)
        # the cells of one encoding are distinct: fancy-index += loses no update
        for heat, data in (
            (self.heat_original, record.heat_original),
            (self.heat_replay, record.heat_replay),
            (self.heat_off_graph, record.heat_off_graph),
        ):
            cells, counts = read_grid_sums(data)
            heat.reshape(-1)[cells] += counts
        cells, counts, sums = read_grid_sums(record.heat_error, 3)
        self.error_count.reshape(-1)[cells] += counts
        self.error_mm.reshape(-1)[cells] += sums
        self.places_original += np.asarray(record.places_original, np.int64)
        self.places_off_graph += np.asarray(record.places_off_graph, np.int64)
        self.places_replay += np.asarray(record.places_replay, np.int64)
        self.places_error_count += np.asarray(record.places_error_count, np.int64)
        self.places_error_mm += np.asarray(record.places_error_mm, np.int64)
        hp = record.hp
        self.hp_pooled = [a + b for a, b in zip(self.hp_pooled, hp.pooled, strict=True)]
        frames = np.array(
            [hp.frame_count, hp.frame_sum_original, hp.frame_sum_replay], np.int64
        ).reshape(3, -1)
        if frames.shape[1] > self.hp_frames.shape[1]:
            grown = np.zeros((3, frames.shape[1]), np.int64)
            grown[:, : self.hp_frames.shape[1]] = self.hp_frames
            self.hp_frames = grown
        self.hp_frames[:, : frames.shape[1]] += frames
        bins = np.array(
            [
                hp.bin_count,
                hp.bin_sum_original,
                hp.bin_sum2_original,
                hp.bin_sum_replay,
                hp.bin_sum2_replay,
            ],
            np.int64,
        ).reshape(5, -1)
        self.hp_bins[:, hp.bin_first : hp.bin_first + bins.shape[1]] += bins

    def hp_by_round(self) -> np.ndarray:
        """(rounds, 7) the `HpStats.pooled` sums of each round, in `round_rows` order."""
        return np.array([self._hp_rounds[key] for key in sorted(self._rows)], np.float64).reshape(
            -1, 7
        )

    def players(self) -> pd.DataFrame:
        """players.csv: one row per player-round, rounds in (match, round) order."""
        rows = [row for key in sorted(self._rows) for row in self._rows[key][1]]
        names = metric_names(self.settings.fastdtw)
        return pd.DataFrame(rows, columns=[*PLAYER_COLUMNS, *names, "reason"])

    def round_rows(self) -> pd.DataFrame:
        """rounds.csv: one row per round, in (match, round) order."""
        rows = [self._rows[key][0] for key in sorted(self._rows)]
        return pd.DataFrame(rows, columns=list(ROUND_COLUMNS))


@dataclass(frozen=True)
class Tables:
    """Every aggregate of an evaluation (see the module docstring)."""

    players: pd.DataFrame
    rounds: pd.DataFrame
    summary: MetricSummary
    trajectory: pd.DataFrame
    """protocol, metric, group, n, mean, std, median, p90, paper_mean, paper_std, and the 95%
    bootstrap intervals by round of the mean and median (`evaluate.intervals`)."""
    combat: pd.DataFrame
    """metric, value, n, paper, note."""
    deaths: DeathTimeMetrics
    outcome: OutcomeMetrics | None
    """None when no round has its winner recorded."""
    hp_curve: pd.DataFrame
    """t_s (bin start), n, original_mean, original_std, replay_mean, replay_std."""
    places: pd.DataFrame
    """place, original_share, replay_share, difference_pp, mean_error_m, off_graph_share and
    sample counts."""
    rounds_both_teams: int
    rounds_with_winner: int
    rounds_with_warnings: int
    """Rounds replayed with implausible data (`--implausible warn`)."""
    rounds_with_contradictions: int
    """Rounds whose frames and events contradict each other (`decoy_cli.replay.missing`)."""
    rounds_with_inferred: int
    """Rounds with fields the data lacked, filled by rule (`decoy_cli.replay.missing`)."""
    bomb: BombMetrics | None = None
    """Bomb fidelity over the rounds whose data records the bomb; None with the bomb off."""


def build_tables(acc: Accumulator) -> Tables:
    """All tables of the accumulated rounds."""
    players = acc.players()
    rounds = acc.round_rows()
    names = metric_names(acc.settings.fastdtw)
    summary = summarize(players[["side", *names, "reason"]], names)
    seed = acc.settings.seed
    trajectory = trajectory_intervals(trajectory_table(summary), players, seed)
    fights = _fight_deaths(players, acc.settings)
    deaths = death_time_metrics(
        fights["death_time_original_s"].to_numpy(np.float64),
        fights["death_time_replay_s"].to_numpy(np.float64),
    )
    known = rounds[rounds["winner_original"].notna()]
    outcome = None
    if len(known):
        with_reasons = known["reason_original"].notna().all()
        outcome = outcome_metrics(
            known["winner_original"].tolist(),
            known["winner_replay"].fillna(UNDECIDED).tolist(),
            known["reason_original"].tolist() if with_reasons else None,
            known["reason_replay"].fillna(END_OF_DATA).tolist() if with_reasons else None,
        )
    hp_values, hp_reasons, hp_n = hp_metrics_from_sums(acc.hp_pooled, acc.hp_frames)
    combat = _combat_table(hp_values, hp_reasons, hp_n, deaths, outcome, len(known))
    if outcome is not None:
        # how many replay outcomes came from playing on after the data (ReplayOptions.play_out)
        after = float((known["played_out_s"] > 0).mean())
        note = "share of rounds decided by playing on after the data's last frame"
        combat.loc[len(combat)] = ("decided_after_data", after, len(known), math.nan, note)
    combat = combat_intervals(combat, fights, rounds, acc.hp_by_round(), seed)
    both = 0
    if len(rounds):
        both_teams = (rounds["players_t"] > 0) & (rounds["players_ct"] > 0)
        both = int(both_teams.sum())
    if both:
        kills = kill_table(rounds[both_teams], seed).assign(paper=math.nan)
        combat = pd.concat([combat, kills[combat.columns]], ignore_index=True)
    if not (acc.settings.combat and acc.settings.deaths == "data"):
        combat["paper"] = math.nan  # the paper's figures come from deaths that follow the data
    return Tables(
        players=players,
        rounds=rounds,
        summary=summary,
        trajectory=trajectory,
        combat=combat,
        deaths=deaths,
        outcome=outcome,
        hp_curve=_hp_curve(acc),
        places=_places(acc),
        rounds_both_teams=both,
        rounds_with_winner=len(known),
        rounds_with_warnings=_count_filled(rounds, "warnings"),
        rounds_with_contradictions=_count_filled(rounds, "contradictions"),
        rounds_with_inferred=_count_filled(rounds, "inferred"),
        bomb=bomb_metrics(rounds, seed=seed) if acc.settings.bomb else None,
    )


def _count_filled(rounds: pd.DataFrame, column: str) -> int:
    """Rounds with something in a text column of notes ("" when none)."""
    return int((rounds[column] != "").sum()) if len(rounds) else 0


def _fight_deaths(players: pd.DataFrame, settings: EvalSettings) -> pd.DataFrame:
    """The players with the deaths the death-time metrics compare: with the fight deciding
    (`--deaths simulated`), a death scripted from the data (the fight did not kill within the
    window, `decoy_cli.replay.replayer`) counts as not died in the replay."""
    if not (settings.combat and settings.deaths == "simulated") or not len(players):
        return players
    scripted = players["death"] == "scripted"
    return players.assign(
        death_time_replay_s=players["death_time_replay_s"].where(~scripted, np.nan)
    )


def trajectory_table(summary: MetricSummary) -> pd.DataFrame:
    """The summary's statistics with the protocol and the paper's Table 2 beside them."""
    table = summary.table.copy()
    protocol = ["clock" if m in METRIC_NAMES_CLOCK else "paper" for m in table["metric"]]
    table.insert(0, "protocol", protocol)
    paper = [
        PAPER_TABLE2.get(g, {}).get(PAPER_VALUE_OF.get(m, m), (math.nan, math.nan))
        for g, m in zip(table["group"], table["metric"], strict=True)
    ]
    table["paper_mean"] = [mean for mean, _ in paper]
    table["paper_std"] = [std for _, std in paper]
    order = table["metric"].map(ALL_METRIC_NAMES.index) * len(GROUPS) + table["group"].map(
        GROUPS.index
    )
    return table.iloc[np.argsort(order.to_numpy(), kind="stable")].reset_index(drop=True)


def hp_metrics_from_sums(
    pooled: list[int], frames: np.ndarray
) -> tuple[dict[str, float], dict[str, str], int]:
    """`hp_corr`, `paper_hp_corr`, `hp_rmse` (values, reasons of NaNs, player-frames) from the
    integer sums of `HpStats`: Pearson from exact integer moments, the mean curves from the
    per-frame sums (the same definitions as `decoy_cli.metrics.hp_metrics`)."""
    n, so, ss, soo, sss, sos, sdd = pooled
    values: dict[str, float] = {}
    reasons: dict[str, str] = {}
    var_o = n * soo - so * so
    var_s = n * sss - ss * ss
    if n < 2:
        values["hp_corr"], reasons["hp_corr"] = math.nan, "fewer than 2 values"
    elif var_o == 0:
        values["hp_corr"], reasons["hp_corr"] = math.nan, "original series is constant"
    elif var_s == 0:
        values["hp_corr"], reasons["hp_corr"] = math.nan, "simulated series is constant"
    else:
        r = (n * sos - so * ss) / (math.sqrt(var_o) * math.sqrt(var_s))
        values["hp_corr"] = min(1.0, max(-1.0, r))
    seen = frames[0] > 0
    mean_o = frames[1, seen] / frames[0, seen]
    mean_s = frames[2, seen] / frames[0, seen]
    values["paper_hp_corr"], reason = pearson(mean_o, mean_s)
    if reason is not None:
        reasons["paper_hp_corr"] = reason
    if n:
        values["hp_rmse"] = math.sqrt(sdd / n)
    else:
        values["hp_rmse"], reasons["hp_rmse"] = math.nan, "no player-frames"
    return values, reasons, n


def _combat_table(
    hp_values: dict[str, float],
    hp_reasons: dict[str, str],
    hp_n: int,
    deaths: DeathTimeMetrics,
    outcome: OutcomeMetrics | None,
    rounds_with_winner: int,
) -> pd.DataFrame:
    rows = []
    for name in ("hp_corr", "paper_hp_corr", "hp_rmse"):
        rows.append((name, hp_values[name], hp_n, hp_reasons.get(name, "player-frames")))
    n_both = deaths.counts["died_both"]
    for name in ("death_time_corr", "death_time_mae_s"):
        rows.append((name, deaths.values[name], n_both, deaths.reasons.get(name, "died in both")))
    for name in ("outcome_agreement", "end_reason_agreement"):
        if outcome is None:
            rows.append((name, math.nan, 0, "no round has its winner recorded"))
        else:
            rows.append(
                (
                    name,
                    outcome.values[name],
                    rounds_with_winner,
                    outcome.reasons.get(name, "rounds"),
                )
            )
    return pd.DataFrame(
        [
            {"metric": m, "value": v, "n": n, "paper": PAPER_COMBAT.get(m, math.nan), "note": note}
            for m, v, n, note in rows
        ]
    )


def _hp_curve(acc: Accumulator) -> pd.DataFrame:
    count, sum_o, sum2_o, sum_s, sum2_s = acc.hp_bins
    seen = np.flatnonzero(count > 0)
    n = count[seen].astype(np.float64)

    def mean_std(total: np.ndarray, total2: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        mean = total[seen] / n
        with np.errstate(invalid="ignore", divide="ignore"):
            var = (total2[seen] - total[seen] * mean) / (n - 1)
        return mean, np.sqrt(np.where(n > 1, np.maximum(var, 0.0), np.nan))

    mean_o, std_o = mean_std(sum_o, sum2_o)
    mean_s, std_s = mean_std(sum_s, sum2_s)
    return pd.DataFrame(
        {
            "t_s": seen * acc.settings.hp_bin_s,
            "n": count[seen],
            "original_mean": mean_o,
            "original_std": std_o,
            "replay_mean": mean_s,
            "replay_std": std_s,
        }
    )


def _places(acc: Accumulator) -> pd.DataFrame:
    """Share of alive samples by nav place, original and replay, the replay's mean distance
    from the player there (by the player's place), and the share of the player's samples with
    no waypoint on their floor; places ordered by the error."""
    names = acc.place_names
    total_o = max(int(acc.places_original.sum()), 1)
    total_r = max(int(acc.places_replay.sum()), 1)
    with np.errstate(invalid="ignore", divide="ignore"):
        error = acc.places_error_mm / 1000 / acc.places_error_count
    table = pd.DataFrame(
        {
            "place": names,
            "original_share": acc.places_original / total_o,
            "replay_share": acc.places_replay / total_r,
            "difference_pp": 100 * (acc.places_replay / total_r - acc.places_original / total_o),
            "mean_error_m": error,
            "off_graph_share": acc.places_off_graph / np.maximum(acc.places_original, 1),
            "original_samples": acc.places_original,
            "replay_samples": acc.places_replay,
            "error_samples": acc.places_error_count,
        }
    )
    table = table[(table["original_samples"] > 0) | (table["replay_samples"] > 0)]
    order = np.argsort(-table["mean_error_m"].fillna(-1).to_numpy(), kind="stable")
    return table.iloc[order].reset_index(drop=True)
