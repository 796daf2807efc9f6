"""Replay fidelity metrics, exactly as defined in docs/metrics.md.

* `distances`: exact DTW (with the warping-path length) and discrete Fréchet kernels, in one
  pruned sweep.
* `trajectory_kernel`: the compiled per-player-round core of the trajectory metrics.
* `fastdtw_metric`: the paper's DTW as the paper computed it (the `fastdtw` package).
* `trajectory`: the ten trajectory metrics of a player-round, protocols "clock" and "paper".
* `combat`: HP, death-time and round-outcome metrics of full rounds.
* `bomb`: plant and defuse agreement and their time, site and position errors over rounds.
* `aggregate`: mean, std, median and p90 by side and overall, with unevaluated rows accounted for.
* `players`: the per-player fidelity table of a replayed round (`player_metrics`).
"""

from decoy_cli.metrics.aggregate import GROUPS, SIDES, MetricSummary, summarize
from decoy_cli.metrics.bomb import BOMB_METRIC_NAMES, BombMetrics, bomb_metrics
from decoy_cli.metrics.combat import (
    DEATH_COUNT_NAMES,
    DEATH_TIME_METRIC_NAMES,
    HP_METRIC_NAMES,
    OUTCOME_METRIC_NAMES,
    DeathTimeMetrics,
    HpMetrics,
    OutcomeMetrics,
    confusion_matrix,
    death_time_metrics,
    hp_metrics,
    outcome_metrics,
    pearson,
)
from decoy_cli.metrics.distances import (
    TIE_RTOL,
    CurveDistances,
    dtw,
    dtw_and_frechet,
    dtw_mean,
    frechet,
)
from decoy_cli.metrics.players import PLAYER_METRIC_COLUMNS, ReplayTrace, player_metrics
from decoy_cli.metrics.trajectory import (
    ALL_METRIC_NAMES,
    FASTDTW_METRIC,
    METRIC_NAMES,
    METRIC_NAMES_CLOCK,
    METRIC_NAMES_PAPER,
    PAPER_LENGTH,
    PAPER_PROTOCOL_NAMES,
    PlayerRound,
    TrajectoryMetrics,
    metric_names,
    resample,
    trajectory_metrics,
    trajectory_metrics_frame,
)

__all__ = [
    "ALL_METRIC_NAMES",
    "BOMB_METRIC_NAMES",
    "DEATH_COUNT_NAMES",
    "DEATH_TIME_METRIC_NAMES",
    "FASTDTW_METRIC",
    "GROUPS",
    "HP_METRIC_NAMES",
    "METRIC_NAMES",
    "METRIC_NAMES_CLOCK",
    "METRIC_NAMES_PAPER",
    "OUTCOME_METRIC_NAMES",
    "PAPER_LENGTH",
    "PAPER_PROTOCOL_NAMES",
    "PLAYER_METRIC_COLUMNS",
    "SIDES",
    "TIE_RTOL",
    "BombMetrics",
    "CurveDistances",
    "DeathTimeMetrics",
    "HpMetrics",
    "MetricSummary",
    "OutcomeMetrics",
    "PlayerRound",
    "ReplayTrace",
    "TrajectoryMetrics",
    "bomb_metrics",
    "confusion_matrix",
    "death_time_metrics",
    "dtw",
    "dtw_and_frechet",
    "dtw_mean",
    "frechet",
    "hp_metrics",
    "metric_names",
    "outcome_metrics",
    "pearson",
    "player_metrics",
    "resample",
    "summarize",
    "trajectory_metrics",
    "trajectory_metrics_frame",
]
