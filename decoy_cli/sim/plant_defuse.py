"""The bomb's timed actions, one tick at a time, as `BombRules.step` plays them: the plant, the
detonation and the defuse. Durations are whole tick counts (`RulesConfig`):

* plant: the carrier, alive, inside a bomb-site zone and not moving, wants to plant at tick t0
  ("plant_begin"); the plant completes at t0 + plant_ticks (3.0 s = 180 ticks at 60 Hz) if at
  every tick in between it is still alive, still, in the zone and still wants to; otherwise
  "plant_abort" (data "reason": died, stopped, moved or left_zone; in a replay also
  handed_over or dropped, when the data moves the bomb);
* detonation: at planted_tick + bomb_ticks (40 s = 2400 ticks), checked before any defuse
  progress of that tick, so a defuse must end strictly before the detonation tick;
* defuse: an alive CT that wants to, stands still and is within 1.5 m horizontally and 1.0 m
  vertically of the planted bomb starts at t0 ("defuse_start"; with several candidates the lowest
  agent index, one defuser at a time) and ends at t0 + defuse ticks (10 s = 600 ticks, 5 s = 300
  with a kit); CS:GO cancels a defuse when the defuser moves, so moving aborts it, like dying,
  leaving the range or no longer wanting to ("defuse_aborted").
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from decoy_cli.sim.rules_config import RulesConfig
from decoy_cli.sim.state import Agents, Bomb, BombStatus, SimEvent


def plant_tick(
    tick: int,
    agents: Agents,
    bomb: Bomb,
    wants_plant: np.ndarray,
    moving: np.ndarray,
    site_at: Callable[[np.ndarray], str],
    plant_ticks: int,
) -> list[SimEvent]:
    """One tick of the carrier's plant (mutates `bomb`): it begins, goes on, completes or stops.
    `site_at` names the bomb-site zone at a position ("" if none); `plant_ticks` the plant's
    duration."""
    carrier = bomb.carrier
    if bomb.planter != carrier and (not wants_plant[carrier] or moving[carrier]):
        return []
    site = site_at(agents.position[carrier])
    if bomb.planter == carrier:
        reason = _first_true(
            ("stopped", not wants_plant[carrier]),
            ("moved", bool(moving[carrier])),
            ("left_zone", not site),
        )
        if reason:
            return [abort_plant(tick, bomb, reason)]
        bomb.plant_ticks += 1
        if bomb.plant_ticks < plant_ticks:
            return []
        bomb.status = BombStatus.PLANTED
        bomb.carrier = -1
        bomb.planter = -1
        bomb.site = site
        bomb.planted_tick = tick
        where = bomb.position.tolist()
        return [SimEvent(tick, "plant", carrier, data={"site": site, "position": where})]
    if wants_plant[carrier] and not moving[carrier] and site:
        bomb.planter = carrier
        bomb.plant_ticks = 0
        return [SimEvent(tick, "plant_begin", carrier, data={"site": site})]
    return []


def defuse_tick(
    tick: int,
    agents: Agents,
    bomb: Bomb,
    wants_defuse: np.ndarray,
    moving: np.ndarray,
    cfg: RulesConfig,
) -> list[SimEvent]:
    """One tick of the defuse of the planted bomb (mutates `bomb`): the defuser's goes on,
    completes or stops, and a candidate starts one when nobody defuses."""
    in_range = within(agents.position, bomb.position, cfg.defuse_range_m, cfg.defuse_vertical_m)
    events = []
    defuser = bomb.defuser
    if defuser >= 0:
        reason = _first_true(
            ("died", not agents.alive[defuser]),
            ("stopped", not wants_defuse[defuser]),
            ("moved", bool(moving[defuser])),
            ("out_of_range", not in_range[defuser]),
        )
        if not reason:
            bomb.defuse_ticks += 1
            needed = cfg.defuse_kit_ticks if agents.has_defuser[defuser] else cfg.defuse_ticks
            if bomb.defuse_ticks < needed:
                return []
            bomb.status = BombStatus.DEFUSED
            bomb.defuser = -1
            return [SimEvent(tick, "defuse", defuser, data={"site": bomb.site})]
        events.append(abort_defuse(tick, bomb, reason))
    candidates = np.nonzero(
        agents.alive
        & (agents.side == "CT")
        & np.asarray(wants_defuse, dtype=bool)
        & ~np.asarray(moving, dtype=bool)
        & in_range
    )[0]
    if len(candidates):
        bomb.defuser = int(candidates[0])
        bomb.defuse_ticks = 0
        kit = bool(agents.has_defuser[bomb.defuser])
        events.append(
            SimEvent(tick, "defuse_start", bomb.defuser, data={"site": bomb.site, "kit": kit})
        )
    return events


def explode(tick: int, bomb: Bomb) -> SimEvent:
    """The planted bomb detonates; a defuse under way was too late."""
    data: dict[str, object] = {"site": bomb.site}
    if bomb.defuser >= 0:  # the defuse was too late
        data["defuser"] = bomb.defuser
        bomb.defuser = -1
    bomb.status = BombStatus.EXPLODED
    return SimEvent(tick, "explode", data=data)


def abort_plant(tick: int, bomb: Bomb, reason: str) -> SimEvent:
    """The plant under way stops, for `reason`."""
    planter = bomb.planter
    bomb.planter = -1
    bomb.plant_ticks = 0
    return SimEvent(tick, "plant_abort", planter, data={"reason": reason})


def abort_defuse(tick: int, bomb: Bomb, reason: str) -> SimEvent:
    """The defuse under way stops, for `reason`."""
    defuser = bomb.defuser
    bomb.defuser = -1
    bomb.defuse_ticks = 0
    return SimEvent(tick, "defuse_aborted", defuser, data={"reason": reason})


def within(
    positions: np.ndarray, point: np.ndarray, horizontal_m: float, vertical_m: float
) -> np.ndarray:
    """(N,) bool: which of `positions` (N, 3) lie within `horizontal_m` of `point` horizontally
    and `vertical_m` vertically: the reach of a defuse, and of a bomb pickup (`BombRules`)."""
    offset = positions - point
    return (np.hypot(offset[:, 0], offset[:, 1]) <= horizontal_m) & (
        np.abs(offset[:, 2]) <= vertical_m
    )


def _first_true(*checks: tuple[str, bool]) -> str:
    """The name of the first check that holds ("" if none does): why a plant or defuse stops."""
    return next((name for name, failed in checks if failed), "")
