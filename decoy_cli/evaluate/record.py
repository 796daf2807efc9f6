"""The compact result of one replayed round: what the aggregate tables and figures need.

A `RoundRecord` holds, for one round: the per-player and per-round table rows, 2-D histogram
counts of original and replayed positions on the fixed `HeatGrid` and the replay's distance
error by original position, sample counts and errors by nav place, and HP as integer sums
(pooled, per data frame and per time bin): integers only, so the aggregates are exact and do
not depend on the order in which rounds finish; and the thinned paths and events the view
page draws (`decoy_cli.replay.view_trace`). `build_record` makes it from a replay.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import msgspec
import numpy as np

from decoy_cli.esta import Round
from decoy_cli.esta.frame_rate import frame_rates
from decoy_cli.evaluate.heat import grid_sums
from decoy_cli.metrics import metric_names, player_metrics
from decoy_cli.metrics.hp_sums import HpStats, hp_stats
from decoy_cli.metrics.kills import KILL_COLUMNS
from decoy_cli.metrics.players import REPLAY_COLUMNS
from decoy_cli.replay.bomb_fidelity import BOMB_COLUMNS
from decoy_cli.replay.view_trace import RoundTrace, round_trace

if TYPE_CHECKING:
    from decoy_cli.evaluate.job import RoundTask
    from decoy_cli.replay.replayer import ReplayResult
    from decoy_cli.waypoints.places import PlaceFinder


class RoundRecord(msgspec.Struct, frozen=True):
    """The result of one round (see the module docstring); cached as one msgpack file."""

    key: str
    file_sha: str
    match_id: str
    round_num: int
    round: dict[str, Any]
    """The rounds.csv row, but `file` and `file_sha` (where the content was read and its
    content hash, set by whoever reads it)."""
    players: list[dict[str, Any]]
    heat_original: bytes
    """Alive samples by grid cell of the original position (`grid_sums` encoding)."""
    heat_replay: bytes
    """Alive samples by grid cell of the replayed position."""
    heat_off_graph: bytes
    """Original alive samples with no waypoint on their floor, by grid cell."""
    heat_error: bytes
    """Samples alive in both, with their summed distance original-replay in integer mm, by
    grid cell of the original position (`grid_sums` with weights)."""
    places_original: list[int]
    """Samples by nav place: index i counts `place_names(graph)[i]`."""
    places_off_graph: list[int]
    """Original samples with no waypoint on their floor (the replay cannot stand there)."""
    places_replay: list[int]
    places_error_count: list[int]
    """Samples alive in both by the original position's place, and their summed distance (mm)."""
    places_error_mm: list[int]
    hp: HpStats
    trace: RoundTrace
    """The players' paths, thinned, and the round's events, for the view page."""


PLAYER_COLUMNS = (
    "match",
    "round",
    "player",
    "side",
    "frames_original",
    "frames_replay",
    "died_original",
    "died_replay",
    "death",
    "death_time_original_s",
    "death_time_replay_s",
    "hp_frames",
    "hp_rmse",
    "hp_final_original",
    "hp_final_replay",
    *REPLAY_COLUMNS,
)
"""Columns of a player row before the trajectory metrics and `reason` (players.csv)."""

ROUND_COLUMNS = (
    "match",
    "round",
    "file",
    "file_sha",
    "frames",
    "frame_rate",
    "seconds",
    "players_t",
    "players_ct",
    "winner_original",
    "reason_original",
    "winner_replay",
    "reason_replay",
    "played_out_s",
    "stuck",
    "recoveries",
    "relocations",
    "warnings",
    "contradictions",
    "inferred",
    "smokes",
    "fires",
    "blinds",
    "wall_seconds",
    *BOMB_COLUMNS,
    *KILL_COLUMNS,
)
"""Columns of a round row (rounds.csv); `frame_rate` is the data's median frames per second
(`decoy_cli.esta.frame_rate`); `warnings` holds the implausible data a round was replayed with
under `--implausible warn`, `contradictions` what its frames and events say against each other
(`decoy_cli.replay.missing`), each joined by `WARNING_SEPARATOR` ("" when none); `inferred` the
fields the data lacked and the rules that filled them, joined likewise; `smokes`, `fires` and
`blinds` the data's utility the fight heeded (empty: none in the data, or no shooting); the
bomb columns (`decoy_cli.replay.bomb_fidelity`) are empty when the bomb was off; the kill columns
(`decoy_cli.metrics.kills`) compare deaths and alive counts."""

WARNING_SEPARATOR = " | "


def build_record(
    task: RoundTask, round_: Round, result: ReplayResult, places: PlaceFinder, seconds: float
) -> RoundRecord:
    """The `RoundRecord` of a replayed round (see the module docstring)."""
    settings = task.settings
    rec = result.recording
    metrics = player_metrics(round_, result.trace(), fastdtw=settings.fastdtw)
    frame_seconds = np.asarray(round_.frame_seconds, dtype=np.float64)
    original = np.asarray(round_.position, dtype=np.float64)  # (P, F, 3)
    present = np.asarray(round_.present, dtype=bool)
    alive_o = np.asarray(round_.alive, dtype=bool) & present & np.isfinite(original).all(axis=2)
    alive_r = rec.alive.T & present  # (P, F)
    hp_o = np.asarray(round_.hp, dtype=np.int64)  # (P, F), -1 unknown
    hp_r = rec.hp.T.astype(np.int64)
    hp_known = present & (hp_o >= 0)

    kills = result.kill_row(round_)
    replay_died_at = result.deaths.seconds
    players = []
    for p, row in enumerate(metrics.to_dict("records")):
        replay_death = np.nan
        if row["died_replay"]:  # at its event's tick; else the first frame showing it dead
            last_alive = int(np.flatnonzero(rec.alive[:, p])[-1])
            replay_death = float(frame_seconds[min(last_alive + 1, len(frame_seconds) - 1)])
            if np.isfinite(replay_died_at[p]):
                replay_death = float(replay_died_at[p])
        known = np.flatnonzero(hp_known[p])
        diff = hp_o[p, known] - hp_r[p, known]
        players.append(
            {
                "match": round_.match_id,
                "round": round_.round_num,
                "player": row["player"],
                "side": row["side"],
                "frames_original": int(alive_o[p].sum()),
                "frames_replay": int(alive_r[p].sum()),
                "died_original": bool(row["died_original"]),
                "died_replay": bool(row["died_replay"]),
                "death": row["death"],
                "death_time_original_s": float(result.data_deaths.seconds[p]),
                "death_time_replay_s": replay_death,
                "hp_frames": len(known),
                "hp_rmse": float(np.sqrt(np.mean(diff**2))) if len(known) else np.nan,
                "hp_final_original": int(hp_o[p, known[-1]]) if len(known) else -1,
                "hp_final_replay": int(hp_r[p, known[-1]]) if len(known) else -1,
                **{name: row[name] for name in REPLAY_COLUMNS},
                **{name: float(row[name]) for name in metric_names(settings.fastdtw)},
                "reason": row["reason"],
            }
        )
    sides = [p.side for p in round_.players]
    round_row = {
        "match": round_.match_id,
        "round": round_.round_num,
        "frames": int(round_.num_frames),
        "frame_rate": round(frame_rates(frame_seconds)[0], 3),
        "seconds": float(frame_seconds[-1] - frame_seconds[0]) if len(frame_seconds) else 0.0,
        "players_t": sides.count("T"),
        "players_ct": sides.count("CT"),
        "winner_original": round_.winning_side,
        "reason_original": round_.end_reason,
        "winner_replay": result.outcome.winner if result.outcome else None,
        "reason_replay": result.outcome.reason if result.outcome else None,
        "played_out_s": round(result.played_out_s, 3),
        "stuck": int(metrics["stuck"].sum()),
        "recoveries": int(metrics["recoveries"].sum()),
        "relocations": int(metrics["relocations"].sum()),
        "warnings": WARNING_SEPARATOR.join(result.warnings),
        "contradictions": WARNING_SEPARATOR.join(result.contradictions),
        "inferred": WARNING_SEPARATOR.join(result.inferred),
        **(result.utility or dict.fromkeys(("smokes", "fires", "blinds"))),
        "wall_seconds": round(seconds, 4),
        **(result.bomb_row() or dict.fromkeys(BOMB_COLUMNS)),
        **kills,
    }
    replayed = rec.position.transpose(1, 0, 2)  # (P, F, 3) like the original
    points_o = original[alive_o]  # (M, 3), player-major
    points_r = replayed[alive_r]
    both = alive_o & alive_r
    error_mm = np.rint(1000 * np.linalg.norm(original[both] - replayed[both], axis=1))
    n_places = len(places.names)
    place_o, on_floor = places.find(points_o)
    place_r, _ = places.find(points_r)
    place_both = place_o[both[alive_o]]
    return RoundRecord(
        key=task.key,
        file_sha=task.file_sha,
        match_id=round_.match_id,
        round_num=round_.round_num,
        round=round_row,
        players=players,
        heat_original=grid_sums(settings.grid, points_o),
        heat_replay=grid_sums(settings.grid, points_r),
        heat_off_graph=grid_sums(settings.grid, points_o[~on_floor]),
        heat_error=grid_sums(settings.grid, original[both], error_mm.astype(np.int64)),
        places_original=np.bincount(place_o, minlength=n_places).tolist(),
        places_off_graph=np.bincount(place_o[~on_floor], minlength=n_places).tolist(),
        places_replay=np.bincount(place_r, minlength=n_places).tolist(),
        places_error_count=np.bincount(place_both, minlength=n_places).tolist(),
        places_error_mm=np.bincount(place_both, weights=error_mm, minlength=n_places)
        .astype(np.int64)
        .tolist(),
        hp=hp_stats(
            hp_o[hp_known],
            hp_r[hp_known],
            np.nonzero(hp_known)[1],
            frame_seconds,
            settings.hp_bin_s,
            settings.hp_bins,
        ),
        trace=round_trace(round_, result),
    )
