"""Bomb and round rules of a CS:GO round, advanced tick by tick by the engine (numpy; `carry`,
the one rule compiled stretches apply too, compiled).

Durations are whole tick counts (`RulesConfig`), so every rule fires on an exact tick:

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
  leaving the range or no longer wanting to ("defuse_aborted");
* a carrier that dies drops the bomb where it stood ("bomb_drop"); the first (lowest index)
  alive T within 0.8 m horizontally and 1.0 m vertically picks it up ("bomb_pickup"), from the
  next tick on (unless `auto_pickup` is off: a replay lets the data say who picks it up, and
  drops it where the data does, `BombRules.drop`).

Round end (`BombRules.outcome`), checked in this order:

1. bomb exploded -> T "TargetBombed"; bomb defused -> CT "BombDefused";
2. both sides eliminated on the same tick (damage is applied simultaneously) -> "TerroristsWin"
   if the bomb is planted (a planted bomb denies the CT any elimination win), else CT "CTWin"
   (the T side failed its objective, as when only the T are eliminated);
3. all CT dead -> T "TerroristsWin" (before or after a plant);
4. all T dead and no bomb planted -> CT "CTWin" (after a plant the round goes on until the
   detonation or a defuse);
5. tick >= round_ticks (115 s = 6900 ticks) and no bomb planted -> CT "TargetSaved": a planted
   bomb stops the round clock. A plant that completes on the last tick beats the clock, because
   the engine advances the rules before it asks for the outcome.

A side with no agent at all is never "eliminated": a T-only round (the paper's T-side replay)
ends by detonation, by all T dying (CTWin, or the detonation after a plant) or by time. With
`bomb_enabled=False` (the paper's movement-only evaluation) no bomb logic runs and a round ends
by elimination or time only.

The zones themselves (`SiteZones`, `BOMB_TARGET_BOXES`) live in `decoy_cli.sim.sites` and are
importable from here too.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from decoy_cli.compiled import njit_cached
from decoy_cli.csgo import TICK_RATE, seconds_to_ticks
from decoy_cli.sim.sites import (
    BOMB_TARGET_BOXES,
    BOX_MARGIN_M,
    SITE_REGIONS,
    ZONE_HORIZONTAL_M,
    ZONE_VERTICAL_M,
    Box,
    SiteZones,
)
from decoy_cli.sim.state import Agents, Bomb, BombStatus, RoundOutcome, SimEvent

__all__ = [
    "BOMB_TARGET_BOXES",
    "BOX_MARGIN_M",
    "SITE_REGIONS",
    "ZONE_HORIZONTAL_M",
    "ZONE_VERTICAL_M",
    "BombRules",
    "Box",
    "RulesConfig",
    "SiteZones",
    "seconds_to_ticks",
]


@dataclass(frozen=True)
class RulesConfig:
    """Durations (seconds) and ranges (metres) of the bomb and round rules.

    The durations are converted once to whole tick counts (`round_ticks`, `plant_ticks`,
    `bomb_ticks`, `defuse_ticks`, `defuse_kit_ticks`) by `seconds_to_ticks` (rounded up).
    """

    tick_rate: int = TICK_RATE
    round_time_s: float = 115.0
    plant_s: float = 3.0
    """CS:GO's C4 arm time; the 9 real plants with a `plant_begin` in
    ../shared/data/esta_dust2_events take 3.04 to 3.06 s from `plant_begin` to `plant`
    (benchmarks/studies/bomb_timing_study.py)."""
    bomb_timer_s: float = 40.0
    """CS:GO's C4 timer (mp_c4timer, 40 s in competitive play)."""
    defuse_s: float = 10.0
    """CS:GO's defuse time without a kit."""
    defuse_kit_s: float = 5.0
    """CS:GO's defuse time with a kit; the one real defuse in ../shared/data/esta_dust2_events
    took 5.02 s from `defuse_start` to `defuse` (benchmarks/studies/bomb_timing_study.py)."""
    defuse_range_m: float = 1.5  # horizontal; CS:GO's use range is about 62 u (1.2 m)
    defuse_vertical_m: float = 1.0
    pickup_range_m: float = 0.8  # horizontal
    pickup_vertical_m: float = 1.0
    auto_pickup: bool = True
    """A T walking over a dropped bomb picks it up (CS:GO); a replay turns it off and lets the
    data say who picks it up."""
    bomb_enabled: bool = True
    round_ticks: int = field(init=False)
    plant_ticks: int = field(init=False)
    bomb_ticks: int = field(init=False)
    defuse_ticks: int = field(init=False)
    defuse_kit_ticks: int = field(init=False)

    def __post_init__(self) -> None:
        if isinstance(self.tick_rate, bool) or not isinstance(self.tick_rate, int):
            raise ValueError(f"tick_rate must be an int, got {self.tick_rate!r}")
        positive = {
            "tick_rate": self.tick_rate,
            "round_time_s": self.round_time_s,
            "plant_s": self.plant_s,
            "bomb_timer_s": self.bomb_timer_s,
            "defuse_s": self.defuse_s,
            "defuse_kit_s": self.defuse_kit_s,
            "defuse_range_m": self.defuse_range_m,
            "defuse_vertical_m": self.defuse_vertical_m,
            "pickup_range_m": self.pickup_range_m,
            "pickup_vertical_m": self.pickup_vertical_m,
        }
        for name, value in positive.items():
            if not (math.isfinite(value) and value > 0):
                raise ValueError(f"{name} must be a positive number, got {value!r}")
        for name, seconds in (
            ("round_ticks", self.round_time_s),
            ("plant_ticks", self.plant_s),
            ("bomb_ticks", self.bomb_timer_s),
            ("defuse_ticks", self.defuse_s),
            ("defuse_kit_ticks", self.defuse_kit_s),
        ):
            object.__setattr__(self, name, seconds_to_ticks(seconds, self.tick_rate))


class BombRules:
    """The bomb's life and the round's end; see the module docstring for every rule."""

    def __init__(self, zones: SiteZones, config: RulesConfig | None = None) -> None:
        self.zones = zones
        self.config = config or RulesConfig()
        self._site_seen: tuple[bytes, str] = (b"", "")  # the last carrier position looked up

    def _site_at(self, position: np.ndarray) -> str:
        """The bomb-site zone a carrier stands in ("" if none); a carrier standing still is
        asked about at every tick, so the last answer is kept."""
        key = np.asarray(position, dtype=np.float64).tobytes()
        if key != self._site_seen[0]:
            self._site_seen = (key, str(self.zones.site_of(position)[0]))
        return self._site_seen[1]

    # ---- round start --------------------------------------------------------------------------

    def start(self, agents: Agents, bomb_carrier: int) -> Bomb:
        """The bomb at the round start: carried by `bomb_carrier`, an alive T (-1: no bomb in
        this round). With the bomb disabled there is never a bomb and the carrier is ignored."""
        if not self.config.bomb_enabled or bomb_carrier == -1:
            return Bomb()
        if not 0 <= bomb_carrier < agents.count:
            raise ValueError(f"bomb carrier {bomb_carrier} is not an agent (0..{agents.count - 1})")
        if agents.side[bomb_carrier] != "T" or not agents.alive[bomb_carrier]:
            raise ValueError(f"bomb carrier {bomb_carrier} must be an alive T")
        return Bomb(
            status=BombStatus.CARRIED,
            carrier=int(bomb_carrier),
            position=agents.position[bomb_carrier].copy(),
        )

    def hand_over(self, tick: int, agents: Agents, bomb: Bomb, agent: int) -> list[SimEvent]:
        """Give the bomb to `agent`, an alive T, from whoever holds it or wherever it lies (a
        replay following the data's carrier); a plant in progress by another stops. Nothing
        happens once the bomb is planted, or without the bomb rules."""
        if not self.config.bomb_enabled or bomb.status not in (
            BombStatus.CARRIED,
            BombStatus.DROPPED,
        ):
            return []
        if agents.side[agent] != "T" or not agents.alive[agent] or bomb.carrier == agent:
            return []
        events = []
        if bomb.planter >= 0:
            events.append(self._abort_plant(tick, bomb, "handed_over"))
        bomb.status = BombStatus.CARRIED
        bomb.carrier = int(agent)
        bomb.position = agents.position[agent].copy()
        events.append(
            SimEvent(
                tick, "bomb_pickup", agent, data={"position": bomb.position.tolist(), "data": True}
            )
        )
        return events

    def drop(self, tick: int, agents: Agents, bomb: Bomb, position: np.ndarray) -> list[SimEvent]:
        """The carrier lets the bomb go and it lies at `position` (a replay following the data's
        drop or throw); a plant in progress stops. Nothing happens unless the bomb is carried."""
        if not self.config.bomb_enabled or bomb.status != BombStatus.CARRIED or bomb.carrier < 0:
            return []
        events = []
        if bomb.planter >= 0:
            events.append(self._abort_plant(tick, bomb, "dropped"))
        carrier = bomb.carrier
        bomb.status = BombStatus.DROPPED
        bomb.carrier = -1
        bomb.position = np.asarray(position, dtype=np.float64).copy()
        events.append(
            SimEvent(
                tick, "bomb_drop", carrier, data={"position": bomb.position.tolist(), "data": True}
            )
        )
        return events

    # ---- one tick -----------------------------------------------------------------------------

    def step(
        self,
        tick: int,
        agents: Agents,
        bomb: Bomb,
        wants_plant: np.ndarray,
        wants_defuse: np.ndarray,
        moving: np.ndarray,
    ) -> list[SimEvent]:
        """Advance the bomb by one tick (mutates `bomb`); returns the tick's bomb events."""
        if not self.config.bomb_enabled:
            return []
        events: list[SimEvent] = []
        if bomb.status == BombStatus.CARRIED and bomb.carrier >= 0:
            if not agents.alive[bomb.carrier]:  # killed without `on_death`
                events += self.on_death(tick, bomb.carrier, agents, bomb)
            else:
                carry(bomb.position, agents.position, bomb.carrier)
                events += self._plant(tick, agents, bomb, wants_plant, moving)
        elif bomb.status == BombStatus.DROPPED and self.config.auto_pickup:
            events += self._pickup(tick, agents, bomb)
        elif bomb.status == BombStatus.PLANTED:
            if tick >= bomb.planted_tick + self.config.bomb_ticks:
                events.append(self._explode(tick, bomb))
            else:
                events += self._defuse(tick, agents, bomb, wants_defuse, moving)
        return events

    def watched(self, agents: Agents, bomb: Bomb) -> np.ndarray:
        """(N,) the agents whose wish to plant or defuse may end a quiet stretch
        (`quiet_until`): the carrier of a carried bomb, everyone once it lies or is planted,
        nobody when the bomb is off."""
        watch = np.zeros(agents.count, dtype=bool)
        if not self.config.bomb_enabled:
            return watch
        if bomb.status == BombStatus.CARRIED and bomb.carrier >= 0:
            watch[bomb.carrier] = True
        elif bomb.status != BombStatus.CARRIED:
            watch[:] = True
        return watch

    def carrier(self, bomb: Bomb) -> int:
        """Who carries the bomb (-1: nobody, or no bomb rules): the agent it follows (`carry`)
        on the quiet ticks a compiled stretch glides through, where it does nothing else."""
        if self.config.bomb_enabled and bomb.status == BombStatus.CARRIED:
            return bomb.carrier
        return -1

    def on_death(self, tick: int, agent: int, agents: Agents, bomb: Bomb) -> list[SimEvent]:
        """An agent died: its plant or defuse stops, and the bomb it carried drops where it
        stood."""
        if not self.config.bomb_enabled:
            return []
        events = []
        if bomb.planter == agent:
            events.append(self._abort_plant(tick, bomb, "died"))
        if bomb.defuser == agent:
            events.append(self._abort_defuse(tick, bomb, "died"))
        if bomb.status == BombStatus.CARRIED and bomb.carrier == agent:
            bomb.status = BombStatus.DROPPED
            bomb.carrier = -1
            bomb.position = agents.position[agent].copy()
            events.append(
                SimEvent(tick, "bomb_drop", agent, data={"position": bomb.position.tolist()})
            )
        return events

    def quiet_until(
        self,
        tick: int,
        agents: Agents,
        bomb: Bomb,
        wants_plant: np.ndarray,
        wants_defuse: np.ndarray,
        standing: Callable[[int], bool],
    ) -> int:
        """The last tick through which `step` and `outcome` have nothing to do but let a carried
        bomb follow its carrier, as long as no agent dies or changes what it wants and the
        agents `standing` says have no motion under way stay put; `tick` when the next tick may
        matter (a plant or a defuse under way or wanted where it can start, a dropped bomb that
        can be picked up). The engine crosses such ticks in one go (`Simulator.run`)."""
        last = 1 << 62
        planted = False
        if self.config.bomb_enabled:
            if bomb.status == BombStatus.CARRIED and bomb.carrier >= 0:
                carrier = bomb.carrier
                if not agents.alive[carrier] or bomb.planter == carrier:
                    return tick
                if wants_plant[carrier] and (  # a plant starts once it stands in a zone
                    not standing(carrier) or self._site_at(agents.position[carrier])
                ):
                    return tick
            elif bomb.status == BombStatus.DROPPED:
                if self.config.auto_pickup:
                    return tick
            elif bomb.status == BombStatus.PLANTED:
                if bomb.defuser >= 0 or bool(np.any(wants_defuse & agents.alive)):
                    return tick
                planted = True
                last = bomb.planted_tick + self.config.bomb_ticks - 1
            elif bomb.status != BombStatus.CARRIED:
                return tick
        if not planted:
            last = min(last, self.config.round_ticks - 1)
        return max(tick, last)

    # ---- round end ----------------------------------------------------------------------------

    def outcome(self, tick: int, agents: Agents, bomb: Bomb) -> RoundOutcome | None:
        """How the round ended at this tick, or None while it goes on."""
        planted = False
        if self.config.bomb_enabled:
            if bomb.status == BombStatus.EXPLODED:
                return RoundOutcome("T", "TargetBombed", tick)
            if bomb.status == BombStatus.DEFUSED:
                return RoundOutcome("CT", "BombDefused", tick)
            planted = bomb.status == BombStatus.PLANTED
        t_out = bool(np.any(agents.side == "T")) and agents.alive_of_side("T") == 0
        ct_out = bool(np.any(agents.side == "CT")) and agents.alive_of_side("CT") == 0
        if t_out and ct_out:
            return (
                RoundOutcome("T", "TerroristsWin", tick)
                if planted
                else RoundOutcome("CT", "CTWin", tick)
            )
        if ct_out:
            return RoundOutcome("T", "TerroristsWin", tick)
        if t_out and not planted:
            return RoundOutcome("CT", "CTWin", tick)
        if not planted and tick >= self.config.round_ticks:
            return RoundOutcome("CT", "TargetSaved", tick)
        return None

    # ---- internals ----------------------------------------------------------------------------

    def _plant(
        self,
        tick: int,
        agents: Agents,
        bomb: Bomb,
        wants_plant: np.ndarray,
        moving: np.ndarray,
    ) -> list[SimEvent]:
        carrier = bomb.carrier
        if bomb.planter != carrier and (not wants_plant[carrier] or moving[carrier]):
            return []
        site = self._site_at(agents.position[carrier])
        if bomb.planter == carrier:
            reason = _first_true(
                ("stopped", not wants_plant[carrier]),
                ("moved", bool(moving[carrier])),
                ("left_zone", not site),
            )
            if reason:
                return [self._abort_plant(tick, bomb, reason)]
            bomb.plant_ticks += 1
            if bomb.plant_ticks < self.config.plant_ticks:
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

    def _defuse(
        self,
        tick: int,
        agents: Agents,
        bomb: Bomb,
        wants_defuse: np.ndarray,
        moving: np.ndarray,
    ) -> list[SimEvent]:
        cfg = self.config
        offset = agents.position - bomb.position
        in_range = (np.hypot(offset[:, 0], offset[:, 1]) <= cfg.defuse_range_m) & (
            np.abs(offset[:, 2]) <= cfg.defuse_vertical_m
        )
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
            events.append(self._abort_defuse(tick, bomb, reason))
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

    def _pickup(self, tick: int, agents: Agents, bomb: Bomb) -> list[SimEvent]:
        cfg = self.config
        offset = agents.position - bomb.position
        near = (np.hypot(offset[:, 0], offset[:, 1]) <= cfg.pickup_range_m) & (
            np.abs(offset[:, 2]) <= cfg.pickup_vertical_m
        )
        takers = np.nonzero(agents.alive & (agents.side == "T") & near)[0]
        if not len(takers):
            return []
        bomb.status = BombStatus.CARRIED
        bomb.carrier = int(takers[0])
        bomb.position = agents.position[bomb.carrier].copy()
        return [
            SimEvent(tick, "bomb_pickup", bomb.carrier, data={"position": bomb.position.tolist()})
        ]

    def _explode(self, tick: int, bomb: Bomb) -> SimEvent:
        data: dict[str, object] = {"site": bomb.site}
        if bomb.defuser >= 0:  # the defuse was too late
            data["defuser"] = bomb.defuser
            bomb.defuser = -1
        bomb.status = BombStatus.EXPLODED
        return SimEvent(tick, "explode", data=data)

    @staticmethod
    def _abort_plant(tick: int, bomb: Bomb, reason: str) -> SimEvent:
        planter = bomb.planter
        bomb.planter = -1
        bomb.plant_ticks = 0
        return SimEvent(tick, "plant_abort", planter, data={"reason": reason})

    @staticmethod
    def _abort_defuse(tick: int, bomb: Bomb, reason: str) -> SimEvent:
        defuser = bomb.defuser
        bomb.defuser = -1
        bomb.defuse_ticks = 0
        return SimEvent(tick, "defuse_aborted", defuser, data={"reason": reason})


@njit_cached
def carry(bomb_position, positions, carrier):
    """A carried bomb follows its carrier: `bomb_position` (3,) takes the position of agent
    `carrier` among `positions` (N, 3), in place (-1: nobody carries it; nothing moves). The one
    place the rule is written: `BombRules.step` applies it at every tick it plays, the compiled
    stretches (`quiet_play.play_quiet`) after their glides."""
    if carrier >= 0:
        bomb_position[:] = positions[carrier]


def _first_true(*checks: tuple[str, bool]) -> str:
    """The name of the first check that holds ("" if none does): why a plant or defuse stops."""
    return next((name for name, failed in checks if failed), "")
