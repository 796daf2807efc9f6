"""What a replay reads of the bomb from the data: who carries it frame by frame, where it was
dropped, when and where the plant that completed happened, who defused and when, and what in
the data does not add up.

`read_data_bomb` gathers it once per round (`DataBomb`). The replayer hands the bomb to the
data's carrier at each frame, drops it where the data's carrier let it go, keeps the carrier
inside the bomb site wherever the real one stood in it, wakes the carrier at the real plant
start and the defuser at the real defuse start; the bomb rules (decoy_cli/sim/rules.py) decide
the rest. `decoy_cli.replay.bomb_fidelity` compares the replay's bomb with this record.

Anomalies (a plant with no carrier, a plant outside every site zone, bomb events out of time
order, a defuse of a bomb never planted) do not stop the replay: they are named in
`DataBomb.anomalies`, counted and listed by `replay` and `evaluate`.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pandas as pd

from decoy_cli.csgo import tick_at
from decoy_cli.errors import EstaError
from decoy_cli.esta import Round
from decoy_cli.replay.plans import PlayerPlan
from decoy_cli.sim.engine import Simulator
from decoy_cli.sim.sites import SiteZones
from decoy_cli.sim.state import BombStatus

PLANT_BEGIN_WINDOW_S = 10.0
"""How long before the plant a `plant_begin` event may lie to count as the start of the plant
that completed: the real plants take about 3 s (the rules' `plant_s`); an older one belongs to an
earlier, interrupted attempt or to broken data."""


@dataclass(frozen=True)
class DataPlantRecord:
    """The plant that completed in the data."""

    seconds: float
    """When it completed, on the round's clock: the `plant` event's tick, else `bombPlantTick`
    (docs/metrics.md)."""
    resolution_s: float
    """How long before `seconds` the plant may have completed: 0 for an event's tick; the
    frame interval when `bombPlantTick` is a frame's tick (files that derive it from the first
    frame showing the bomb planted, such as the T-side files)."""
    start_s: float
    """When the plant began: the last `plant_begin` within `PLANT_BEGIN_WINDOW_S` before it,
    else `seconds` minus the plant's duration."""
    planter: int
    """Row of the player who planted (-1 when the data does not say)."""
    site: str
    """"A" or "B" as the data logs it, else the site zone holding `position` ("" in none)."""
    position: np.ndarray | None
    """(3,) metres where the bomb lay once planted (frames), else where the planter stood
    (event); None when the data has neither."""


@dataclass(frozen=True)
class DataDefuse:
    """One defuse attempt in the data: `defuse_start` to its `defuse` or `defuse_aborted`."""

    agent: int
    start_s: float
    end_s: float
    """When it completed or was given up (NaN: the data shows neither)."""
    completed: bool


@dataclass(frozen=True)
class DataBomb:
    """Everything the replay and the bomb fidelity read of one round's bomb (module docstring)."""

    recorded: bool
    """Whether the data records the bomb at all (a carrier in a frame, a bomb event or a plant
    tick): only such rounds enter the bomb fidelity."""
    carriers: np.ndarray
    """(F,) row of the alive player holding the bomb in each frame (-1: nobody)."""
    drops: np.ndarray
    """(F,) bool: frames where nobody holds the bomb, the previous frame's carrier is alive,
    and the bomb is not planted: the data's carrier let it go (a drop or a throw)."""
    plant: DataPlantRecord | None
    defuses: tuple[DataDefuse, ...]
    anomalies: tuple[str, ...]

    @property
    def defused(self) -> DataDefuse | None:
        """The completed defuse, if the data has one."""
        return next((d for d in self.defuses if d.completed), None)


def read_data_bomb(round_: Round, zones: SiteZones, plant_s: float) -> DataBomb:
    """The bomb of one round as the data shows it; a CT carrier is an EstaError (only a T can
    carry the bomb), every other oddity an anomaly (module docstring)."""
    carriers = data_carriers(round_)
    anomalies: list[str] = []
    events = bomb_events(round_, anomalies)
    plant = _plant(round_, events, carriers, zones, plant_s, anomalies)
    defuses = _defuses(round_, events, plant, anomalies)
    planted = np.asarray(round_.bomb_planted, bool)
    if plant is not None:
        planted = planted | (np.asarray(round_.frame_seconds) >= plant.seconds)
    alive = np.asarray(round_.alive, bool)
    before = np.concatenate([[-1], carriers[:-1]])
    before_alive = np.zeros(len(carriers), bool)
    held = np.flatnonzero(before >= 0)
    before_alive[held] = alive[before[held], held]
    drops = (carriers < 0) & (before >= 0) & before_alive & ~planted
    recorded = bool((carriers >= 0).any() or len(events) or round_.bomb_plant_tick is not None)
    return DataBomb(recorded, carriers, drops, plant, tuple(defuses), tuple(anomalies))


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


def follow_data_bomb(sim: Simulator, bomb: DataBomb, frame: int, round_: Round) -> None:
    """At a data frame's tick: the bomb changes hands, or is let go where the data shows it
    lying, as in the data."""
    carrier = int(bomb.carriers[frame])
    if carrier >= 0 and sim.bomb.carrier != carrier:
        sim.hand_bomb(carrier)
    elif bomb.drops[frame] and sim.bomb.status == BombStatus.CARRIED:
        lies = np.asarray(round_.bomb_position[frame], dtype=np.float64)
        sim.drop_bomb(lies if np.isfinite(lies).all() else sim.agents.position[sim.bomb.carrier])


def carrier_sites(round_: Round, carriers: np.ndarray, zones: SiteZones) -> np.ndarray:
    """(P, F) the bomb site the data's carrier stands in at each frame, "" elsewhere and for
    everyone else: where the replay must keep the carrier inside the site."""
    sites = np.full(np.shape(round_.alive), "", dtype=object)
    frames = np.flatnonzero(carriers >= 0)
    if len(frames):
        where = np.asarray(round_.position, dtype=np.float64)[carriers[frames], frames]
        sites[carriers[frames], frames] = zones.site_of(where)
    return sites


@dataclass(frozen=True)
class DataPlant:
    """The data's completed plant as the replay's policy needs it."""

    start_tick: int
    """Simulator tick at which the real carrier began the plant."""
    agent: int
    """The planter (-1: unknown)."""
    target: int
    """Index of the planter's plan target where it planted: its last target before the plant
    (-1 when its plan has none)."""
    arrive_by: int = -1
    """Index of the planter's first target at or after the plant start, when it is the plant
    spot already: the move into it must end by `start_tick` (the real carrier stood there
    planting by then, though the frames only show it at the frame after); -1: no such target."""


def policy_plant(bomb: DataBomb, plans: list[PlayerPlan]) -> DataPlant | None:
    """The data's plant for `PlanPolicy`, None when the data shows no completed plant."""
    plant = bomb.plant
    if plant is None:
        return None
    agent, target, arrive_by = plant.planter, -1, -1
    if agent >= 0:
        own = plans[agent]
        seconds = own.target_seconds
        earlier = np.flatnonzero(seconds < plant.seconds)
        target = int(earlier[-1]) if len(earlier) else -1
        during = np.flatnonzero(seconds >= plant.start_s)
        if target >= 0 and len(during) and 0 < during[0] <= target:
            arrive_by = (
                int(during[0]) if own.target_node[during[0]] == own.target_node[target] else -1
            )
    return DataPlant(tick_at(plant.start_s), agent if target >= 0 else -1, target, arrive_by)


def player_row(round_: Round, name: object, steam_id: object) -> int:
    """The row of the player an event names (by steamID, else name); -1 if none."""
    for i, player in enumerate(round_.players):
        if (steam_id is not None and not pd.isna(steam_id) and player.steam_id == steam_id) or (
            isinstance(name, str) and name and player.name == name
        ):
            return i
    return -1


def data_plant_tick(events: pd.DataFrame, round_: Round) -> float | None:
    """The tick of the data's plant: its first `plant` event's (of `bomb_events`), else the
    round's `bombPlantTick`; None without a plant."""
    plants = events.loc[events["bombAction"] == "plant", "tick"]
    if len(plants):
        return float(plants.iloc[0])
    return None if round_.bomb_plant_tick is None else float(round_.bomb_plant_tick)


def bomb_events(round_: Round, anomalies: list[str]) -> pd.DataFrame:
    """The bomb events with a tick and an action, in time order (an anomaly if the file's order
    was not)."""
    events = round_.bomb_events
    if len(events) == 0 or "bombAction" not in events or "tick" not in events:
        return pd.DataFrame(columns=["tick", "seconds", "bombAction"])
    events = events[events["tick"].notna() & events["bombAction"].notna()]
    ticks = events["tick"].to_numpy(dtype=np.float64)
    if (np.diff(ticks) < 0).any():
        anomalies.append("bomb events out of time order (replayed in time order)")
        events = events.sort_values("tick", kind="stable")
    return events


def _plant(
    round_: Round,
    events: pd.DataFrame,
    carriers: np.ndarray,
    zones: SiteZones,
    plant_s: float,
    anomalies: list[str],
) -> DataPlantRecord | None:
    clock = round_.clock
    plants = events[events["bombAction"] == "plant"]
    plant_tick = data_plant_tick(events, round_)
    if clock is None or plant_tick is None:
        return None
    ticks = np.asarray(round_.frame_ticks)
    resolution = 0.0
    if len(plants) == 0:
        k = int(np.searchsorted(ticks, plant_tick))
        if 0 < k < len(ticks) and ticks[k] == plant_tick:  # derived from the frames
            resolution = (plant_tick - ticks[k - 1]) / clock.tick_rate
    seconds = float(clock.seconds(plant_tick))
    begins = events.loc[events["bombAction"] == "plant_begin", "tick"].to_numpy(np.float64)
    begins = clock.seconds(begins)
    begins = begins[(begins <= seconds) & (begins >= seconds - PLANT_BEGIN_WINDOW_S)]
    start_s = float(begins.max()) if len(begins) else seconds - plant_s

    planter = -1
    if len(plants):
        row = plants.iloc[0]
        planter = player_row(round_, row.get("playerName"), row.get("playerSteamID"))
    if planter < 0:
        held = np.flatnonzero((ticks < plant_tick) & (carriers >= 0))
        planter = int(carriers[held[-1]]) if len(held) else -1
    if planter < 0:
        anomalies.append("plant without a carrier (the replay has nobody to plant)")

    position = None
    planted = np.flatnonzero(np.asarray(round_.bomb_planted, bool))
    bomb_at = np.asarray(round_.bomb_position, dtype=np.float64)
    if len(planted) and np.isfinite(bomb_at[planted[0]]).all():
        position = bomb_at[planted[0]].copy()
    elif len(plants) and all(f"player{a}_m" in plants for a in "XYZ"):
        xyz = plants[["playerX_m", "playerY_m", "playerZ_m"]].iloc[0].to_numpy(np.float64)
        position = xyz if np.isfinite(xyz).all() else None
    site = ""
    if len(plants) and isinstance(plants["bombSite"].iloc[0], str):
        site = str(plants["bombSite"].iloc[0])
    elif len(planted) and str(round_.bombsite[planted[0]]):
        site = str(round_.bombsite[planted[0]])
    zone = str(zones.site_of(position)[0]) if position is not None else ""
    if position is not None and not zone:
        anomalies.append("plant outside every bomb-site zone (the replay cannot plant there)")
    return DataPlantRecord(seconds, resolution, start_s, planter, site or zone, position)


def _defuses(
    round_: Round, events: pd.DataFrame, plant: DataPlantRecord | None, anomalies: list[str]
) -> list[DataDefuse]:
    """Each `defuse_start` with the `defuse` or `defuse_aborted` of the same player after it."""
    clock = round_.clock
    acts = events[events["bombAction"].isin(["defuse_start", "defuse_aborted", "defuse"])]
    if len(acts) == 0 or clock is None:
        return []
    if plant is None:
        anomalies.append("defuse of a bomb never planted (ignored)")
        return []
    out: list[DataDefuse] = []
    open_starts: dict[int, float] = {}
    for _, row in acts.iterrows():
        agent = player_row(round_, row.get("playerName"), row.get("playerSteamID"))
        seconds = float(clock.seconds(float(row["tick"])))
        if agent < 0:
            continue
        if row["bombAction"] == "defuse_start":
            open_starts[agent] = seconds
        elif agent in open_starts:
            completed = row["bombAction"] == "defuse"
            out.append(DataDefuse(agent, open_starts.pop(agent), seconds, completed))
    out += [DataDefuse(agent, start, np.nan, False) for agent, start in open_starts.items()]
    return sorted(out, key=lambda d: d.start_s)


def defuse_windows(bomb: DataBomb) -> dict[int, tuple[int, int]]:
    """Agent -> (first, last) simulator tick of its wish to defuse: from its data defuse start
    (of the attempt that completed, else its first) to the data's end of that attempt; for ever
    after the start of a completed one (the replay's own defuse may end later) or of one whose
    end the data does not show."""
    windows: dict[int, tuple[int, int]] = {}
    for d in sorted(bomb.defuses, key=lambda d: (not d.completed, d.start_s)):
        if d.agent not in windows:  # a round row: `_defuses` keeps only players it found
            end = tick_at(d.end_s) if np.isfinite(d.end_s) and not d.completed else FOREVER
            windows[d.agent] = (tick_at(d.start_s), end)
    return windows


FOREVER = 10**9
"""A simulator tick no round reaches."""
