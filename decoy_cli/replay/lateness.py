"""How late a replay reached the data's targets, and why: the per-player lateness table.

A target is late when the agent reaches it after its tick; a stretch of late targets is put
down to the interval that added most lateness in it (`stretch_causes`).
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from decoy_cli.csgo import TICK_RATE
from decoy_cli.replay.pace import asks_more
from decoy_cli.replay.plans import PlayerPlan
from decoy_cli.replay.policy import AgentLog
from decoy_cli.replay.rounds import RoundPlan

DATA_FRAME_S = 0.5
"""One data frame of ESTA (2 frames per second): a target reached later than this is off by a
whole frame of the data."""


LATE_CAUSES = ("zigzag", "detour", "speed", "gap", "replay")
"""Why a target is late, as `stretch_causes` numbers them (`ReplayTrace` says each)."""


def stretch_causes(plan: PlayerPlan, caps: np.ndarray, late: np.ndarray) -> np.ndarray:
    """(T,) for every target reached late (after its tick), why: an index into `LATE_CAUSES`
    (-1 for a target on time or unreached).

    A late target is put down to the interval that added the most lateness in its stretch of
    late targets (consecutive targets reached late) up to it, judged against the speed the
    replay may run there (`caps`, as `asks_more` judges): unreachable (`gap`); asking more
    than the cap only by the graph's way round something, the straight line between the two
    waypoints would be in time
    (`detour`) or only by the lattice's zig-zag (`zigzag`); asking more even straight
    (`speed`: the waypoints lie farther apart than the player ran, or the player outran the
    cap); within the cap (`replay`: the replay's own delay, a wait or a stop).
    """
    count = len(late)
    interval = np.full(count, LATE_CAUSES.index("replay"), dtype=np.int64)
    if count > 1:
        over, detour, zigzag = asks_more(
            plan.interval_required_speed_m_s,
            plan.interval_straight_run_m,
            plan.interval_running_s,
            plan.interval_run_m,
            caps,
        )
        interval[1:] = np.select(
            [plan.interval_unreachable, zigzag, detour, over],
            [LATE_CAUSES.index(c) for c in ("gap", "zigzag", "detour", "speed")],
            LATE_CAUSES.index("replay"),
        )
    with np.errstate(invalid="ignore"):
        is_late = late > 1 / TICK_RATE + 1e-9
    added = np.diff(np.where(is_late, late, 0.0), prepend=0.0)  # lateness each interval added
    cause = np.full(count, -1, dtype=np.int64)
    worst, most = -1, -np.inf
    for target in np.flatnonzero(is_late).tolist():
        if target == 0 or not is_late[target - 1]:
            worst, most = target, -np.inf  # a new stretch
        if added[target] > most:
            worst, most = target, float(added[target])
        cause[target] = interval[worst]
    return cause


def lateness_table(plan: RoundPlan, logs: list[AgentLog]) -> pd.DataFrame:
    """Per player: targets, those reached, the share reached late (after their tick), how
    many more than one data frame late (`DATA_FRAME_S`) and why (`late_zigzag`,
    `late_detour`, `late_speed`, `late_gap`, `late_replay`: see `ReplayTrace`), p95 and
    max lateness (s), relocations."""
    rows = []
    for p, log in enumerate(logs):
        late = log.lateness_s
        reached = late[np.isfinite(late)]
        with np.errstate(invalid="ignore"):
            over = late > DATA_FRAME_S + 1e-9  # unreached (NaN): not
        cause = stretch_causes(plan.plans[p], plan.caps[p], late)
        rows.append(
            {
                "player": plan.players[p].name,
                "targets": len(late),
                "reached": len(reached),
                "late_share": float(np.mean(reached > 1 / TICK_RATE + 1e-9))
                if len(reached)
                else np.nan,
                "late_over_frame": int(over.sum()),
                **{
                    f"late_{name}": int(np.sum(over & (cause == k)))
                    for k, name in enumerate(LATE_CAUSES)
                },
                "late_p95_s": float(np.percentile(reached, 95)) if len(reached) else np.nan,
                "late_max_s": float(reached.max()) if len(reached) else np.nan,
                "relocations": log.relocations,
            }
        )
    return pd.DataFrame(rows)
