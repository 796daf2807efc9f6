"""Replay of real rounds: snap data-frame positions to waypoints, fill gaps, build timed plans,
and replay them in the simulator (`replay_round`)."""

from decoy_cli.replay.plans import (
    ACTION_NAMES,
    RELOCATE_ACTION,
    PathCache,
    PlayerPlan,
    build_plan,
)
from decoy_cli.replay.replayer import ReplayOptions, ReplayResult, replay_round
from decoy_cli.replay.rounds import SUMMARY_COLUMNS, RoundPlan, snap_round
from decoy_cli.replay.snapping import (
    DEFAULT_MAX_SNAP_M,
    SnapResult,
    SnapStatus,
    snap_positions,
)

__all__ = [
    "ACTION_NAMES",
    "DEFAULT_MAX_SNAP_M",
    "RELOCATE_ACTION",
    "SUMMARY_COLUMNS",
    "PathCache",
    "PlayerPlan",
    "ReplayOptions",
    "ReplayResult",
    "RoundPlan",
    "SnapResult",
    "SnapStatus",
    "build_plan",
    "replay_round",
    "snap_positions",
    "snap_round",
]
