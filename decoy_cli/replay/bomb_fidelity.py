"""How faithfully a replay's bomb follows the data, for one round: the `BOMB_COLUMNS` of its row.

The data side is `DataBomb` (decoy_cli/replay/bomb.py); the replay side is the simulator's
events. Times are seconds on the round's clock, signed replay minus data; positions metres.
docs/metrics.md defines every column and `decoy_cli.metrics.bomb` aggregates them.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import TypedDict

import numpy as np

from decoy_cli.csgo import TICK_RATE
from decoy_cli.replay.bomb import DataBomb
from decoy_cli.sim.state import SimEvent

ANOMALY_SEPARATOR = " | "

BOMB_COLUMNS = (
    "bomb_recorded",
    "plant_data",
    "plant_replay",
    "plant_time_error_s",
    "plant_time_resolution_s",
    "plant_site_data",
    "plant_site_replay",
    "plant_position_error_m",
    "defuse_data",
    "defuse_replay",
    "defuse_time_error_s",
    "bomb_anomalies",
)
"""The bomb columns of a round row (rounds.csv, the replay's summary.json)."""


class BombRow(TypedDict):
    """A round's `BOMB_COLUMNS` (`bomb_fidelity`)."""

    bomb_recorded: bool
    plant_data: bool
    plant_replay: bool
    plant_time_error_s: float
    plant_time_resolution_s: float
    plant_site_data: str
    plant_site_replay: str
    plant_position_error_m: float
    defuse_data: bool
    defuse_replay: bool
    defuse_time_error_s: float
    bomb_anomalies: str


def bomb_fidelity(data: DataBomb, events: Sequence[SimEvent]) -> BombRow:
    """The round's `BOMB_COLUMNS`: whether the data and the replay planted and defused, the
    plant's time, site and position errors and the defuse's time error (NaN unless both did),
    and the data's anomalies joined by `ANOMALY_SEPARATOR`."""
    plant = next((e for e in events if e.kind == "plant"), None)
    defuse = next((e for e in events if e.kind == "defuse"), None)
    data_plant = data.plant
    data_defuse = data.defused
    time_error = position_error = defuse_error = np.nan
    if plant is not None and data_plant is not None:
        time_error = plant.tick / TICK_RATE - data_plant.seconds
        where = plant.data.get("position")
        if where is not None and data_plant.position is not None:
            offset = np.asarray(where, dtype=np.float64) - data_plant.position
            position_error = float(np.linalg.norm(offset))
    if defuse is not None and data_defuse is not None:
        defuse_error = defuse.tick / TICK_RATE - data_defuse.end_s
    return {
        "bomb_recorded": data.recorded,
        "plant_data": data_plant is not None,
        "plant_replay": plant is not None,
        "plant_time_error_s": _rounded(time_error),
        "plant_time_resolution_s": _rounded(data_plant.resolution_s if data_plant else np.nan),
        "plant_site_data": data_plant.site if data_plant else "",
        "plant_site_replay": str(plant.data.get("site", "")) if plant is not None else "",
        "plant_position_error_m": _rounded(position_error),
        "defuse_data": data_defuse is not None,
        "defuse_replay": defuse is not None,
        "defuse_time_error_s": _rounded(defuse_error),
        "bomb_anomalies": ANOMALY_SEPARATOR.join(data.anomalies),
    }


def _rounded(value: float) -> float:
    """Milliseconds or millimetres are the data's precision: no float noise in the tables."""
    return float(np.round(value, 4)) if np.isfinite(value) else float("nan")
