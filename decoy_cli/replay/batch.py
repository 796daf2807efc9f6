"""Replay many rounds and collect their metrics, with per-round failures recorded.

One physics world serves all rounds of a call. A round that cannot be replayed (an unreadable
file, a round whose data is broken, an unknown weapon) becomes a `Failure` and the batch goes on.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Iterable
from dataclasses import dataclass, field
from pathlib import Path

import pandas as pd

from decoy_cli.errors import DecoyError
from decoy_cli.esta import read_match
from decoy_cli.replay.output import player_metrics
from decoy_cli.replay.replayer import ReplayOptions, replay_round
from decoy_cli.waypoints.graph import WaypointGraph
from decoy_cli.world.navmesh import nav_world
from decoy_cli.world.physics import PhysicsWorld


@dataclass(frozen=True)
class Failure:
    """A file or round that could not be replayed, and why (one line)."""

    file: str
    round_num: int | None
    message: str


@dataclass
class BatchResult:
    """Per player-round rows, per-round rows, and failures."""

    players: pd.DataFrame
    rounds: pd.DataFrame
    failures: list[Failure] = field(default_factory=list)


def replay_files(
    files: Iterable[Path],
    graph: WaypointGraph,
    options: ReplayOptions,
    on_round: Callable[[int], None] | None = None,
) -> BatchResult:
    """Replay every round of the files; `on_round(count)` is called after each round."""
    player_rows: list[pd.DataFrame] = []
    round_rows: list[dict] = []
    failures: list[Failure] = []
    done = 0
    with PhysicsWorld(nav_world()) as physics:
        for file in files:
            try:
                match = read_match(file)
            except DecoyError as error:
                failures.append(Failure(str(file), None, str(error)))
                continue
            for num, error in match.round_errors.items():
                failures.append(Failure(str(file), num, str(error)))
            for round_ in match.rounds:
                started = time.perf_counter()
                try:
                    result = replay_round(round_, graph, physics, options)
                except DecoyError as error:
                    failures.append(Failure(str(file), round_.round_num, str(error)))
                    continue
                table = player_metrics(round_, result)
                table.insert(0, "round", round_.round_num)
                table.insert(0, "match", match.match_id)
                player_rows.append(table)
                round_rows.append(
                    {
                        "match": match.match_id,
                        "round": round_.round_num,
                        "frames": round_.num_frames,
                        "winner_original": round_.winning_side,
                        "reason_original": round_.end_reason,
                        "winner_replay": result.outcome.winner if result.outcome else None,
                        "reason_replay": result.outcome.reason if result.outcome else None,
                        "stuck": int(table["stuck"].sum()),
                        "recoveries": int(table["recoveries"].sum()),
                        "relocations": int(table["relocations"].sum()),
                        "wall_seconds": time.perf_counter() - started,
                    }
                )
                done += 1
                if on_round is not None:
                    on_round(done)
    players = pd.concat(player_rows, ignore_index=True) if player_rows else pd.DataFrame()
    return BatchResult(players=players, rounds=pd.DataFrame(round_rows), failures=failures)
