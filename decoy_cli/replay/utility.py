"""The data's smokes, fires and blinds as a replay's fight heeds them (decoy_cli/sim/utility.py):
each at its real window on the simulator's clock, a blind on the agent the data names.

A smoke or fire the data shows no end of is not used (the reader names it), nor a blind of a
player the frames do not hold. A round without any is replayed as before, and says so.
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from decoy_cli.csgo import tick_at
from decoy_cli.esta import Round
from decoy_cli.replay.bomb import player_row
from decoy_cli.sim.utility import Utility


def round_utility(round_: Round) -> Utility | None:
    """The round's utility on the simulator's clock; None where the round has none."""
    smoke_at, smoke_start, smoke_end = _windows(round_.smokes)
    fire_at, fire_start, fire_end = _windows(round_.fires)
    agents, starts, ends = [], [], []
    flashes = round_.flashes
    for row in flashes.itertuples() if len(flashes) else ():
        agent = player_row(round_, row.playerName, row.playerSteamID)
        duration = float(row.flashDuration) if not pd.isna(row.flashDuration) else np.nan
        if agent < 0 or pd.isna(row.seconds) or not duration > 0:
            continue
        agents.append(agent)
        starts.append(tick_at(float(row.seconds)))
        ends.append(tick_at(float(row.seconds) + duration))
    if not (len(smoke_start) or len(fire_start) or agents):
        return None
    return Utility(
        smoke_at=smoke_at,
        smoke_start=smoke_start,
        smoke_end=smoke_end,
        fire_at=fire_at,
        fire_start=fire_start,
        fire_end=fire_end,
        blind_agent=np.array(agents, dtype=np.int64),
        blind_start=np.array(starts, dtype=np.int64),
        blind_end=np.array(ends, dtype=np.int64),
    )


def _windows(table: pd.DataFrame) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Centres (K, 3) metres and [start, end) ticks of the smokes or fires with an end."""
    whole = table[np.isfinite(table["start_s"]) & np.isfinite(table["end_s"])]
    centres = whole[["x_m", "y_m", "z_m"]].to_numpy(dtype=np.float64).reshape(-1, 3)
    start = np.array([tick_at(s) for s in whole["start_s"]], dtype=np.int64)
    end = np.array([tick_at(s) for s in whole["end_s"]], dtype=np.int64)
    return centres, start, end
