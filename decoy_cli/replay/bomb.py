"""What a replay reads of the bomb from the data: who carries it frame by frame, when the plant
that completed began, and from when each defuser wants to defuse.

The replayer hands the bomb to the data's carrier at each frame (`data_carriers`), keeps the
carrier inside the bomb site wherever the real one stood in it (`carrier_sites`), wakes the
carrier at the real plant start (`data_plant_start_s`) and lets a defuser try from its first
`defuse_start` (`data_defuse_starts`); the bomb rules (decoy_cli/sim/rules.py) decide the rest.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from decoy_cli.csgo import TICK_RATE, tick_at
from decoy_cli.errors import EstaError
from decoy_cli.esta import PlayerInfo, Round
from decoy_cli.replay.plans import PlayerPlan
from decoy_cli.sim.sites import SiteZones

PLANT_BEGIN_WINDOW_S = 10.0
"""How long before the plant a `plant_begin` event may lie to count as the start of the plant
that completed: the real plants take about 3 s (the rules' `plant_s`); an older one belongs to an
earlier, interrupted attempt or to broken data."""


def data_carriers(round_: Round) -> np.ndarray:
    """(F,) row of the alive player holding the bomb in each frame (-1: nobody). A CT holding
    it is an EstaError naming the first such frame: only a T can carry the bomb."""
    holding = np.asarray(round_.has_bomb, bool) & np.asarray(round_.alive, bool)
    carriers = np.where(holding.any(axis=0), np.argmax(holding, axis=0), -1)
    ct = np.array([p.side != "T" for p in round_.players], bool)
    wrong = np.flatnonzero((carriers >= 0) & ct[np.maximum(carriers, 0)])
    if len(wrong):
        f = int(wrong[0])
        player = round_.players[int(carriers[f])]
        raise EstaError(
            f"{round_.path}: round {round_.round_num}: {player.name} on the {player.side} side "
            f"holds the bomb at frame {f}: only a T can carry it"
        )
    return carriers


def carrier_sites(round_: Round, carriers: np.ndarray, zones: SiteZones) -> np.ndarray:
    """(P, F) the bomb site the data's carrier (`data_carriers`) stands in at each frame, ""
    elsewhere and for everyone else: where the replay must keep the carrier inside the site."""
    sites = np.full(np.shape(round_.alive), "", dtype=object)
    frames = np.flatnonzero(carriers >= 0)
    if len(frames):
        where = np.asarray(round_.position, dtype=np.float64)[carriers[frames], frames]
        sites[carriers[frames], frames] = zones.site_of(where)
    return sites


def data_plant_start_s(round_: Round, plant_s: float) -> float | None:
    """When the real carrier began the plant that completed (seconds on the round's clock): the
    last `plant_begin` event within `PLANT_BEGIN_WINDOW_S` before the plant, else the plant tick
    minus the plant's duration `plant_s` (the T-side files record only `bombPlantTick`); None
    when the data shows no completed plant."""
    if round_.bomb_plant_tick is None or round_.clock is None:
        return None
    plant_at = float(round_.clock.seconds(round_.bomb_plant_tick))
    events = round_.bomb_events
    if len(events) and "bombAction" in events and "seconds" in events:
        begins = events.loc[events["bombAction"] == "plant_begin", "seconds"].to_numpy(float)
        begins = begins[(begins <= plant_at) & (begins >= plant_at - PLANT_BEGIN_WINDOW_S)]
        if len(begins):
            return float(begins.max())
    return plant_at - plant_s


@dataclass(frozen=True)
class DataPlant:
    """The plant that completed in the data, as the replay's policy needs it."""

    start_tick: int
    """Simulator tick at which the real carrier began the plant (`data_plant_start_s`)."""
    agent: int
    """The data's carrier just before the plant (-1: nobody held the bomb in those frames)."""
    target: int
    """Index of the carrier's plan target where it planted: its last target before the plant
    (-1 when its plan has none)."""


def data_plant(
    round_: Round, plans: list[PlayerPlan], carriers: np.ndarray, plant_s: float
) -> DataPlant | None:
    """The data's completed plant: when it began, who planted and at which plan target; None
    when the data shows no completed plant."""
    start_s = data_plant_start_s(round_, plant_s)
    if start_s is None or round_.bomb_plant_tick is None:
        return None
    before = np.flatnonzero(
        (np.asarray(round_.frame_ticks) < round_.bomb_plant_tick) & (carriers >= 0)
    )
    agent = int(carriers[before[-1]]) if len(before) else -1
    target = -1
    if agent >= 0:
        earlier = np.flatnonzero(plans[agent].target_frame <= before[-1])
        target = int(earlier[-1]) if len(earlier) else -1
    return DataPlant(tick_at(start_s), agent if target >= 0 else -1, target)


def data_defuse_starts(round_: Round, players: list[PlayerInfo]) -> dict[int, int]:
    """Agent -> tick from which it wants to defuse: its `defuse_start` events in the data."""
    events = round_.bomb_events
    if len(events) == 0 or "bombAction" not in events:
        return {}
    starts = events[events["bombAction"] == "defuse_start"]
    out: dict[int, int] = {}
    for i, player in enumerate(players):
        mine = starts[
            (starts.get("playerName") == player.name)
            | (starts.get("playerSteamID") == player.steam_id)
        ]
        if len(mine):
            seconds = float(np.nanmin(mine["seconds"])) if "seconds" in mine else np.nan
            if np.isfinite(seconds):
                out[i] = tick_at(seconds) - TICK_RATE
    return out
