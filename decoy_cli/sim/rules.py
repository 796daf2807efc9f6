"""The bomb and the round's rules, advanced tick by tick by the engine (numpy; `carry`, the one
rule compiled stretches apply too, compiled). `BombRules` holds them: who has the bomb, and each
tick's rule by the bomb's state:

* carried: it follows its carrier (`carry`), who may plant it (decoy_cli/sim/plant_defuse.py,
  with the detonation and the defuse once it is planted);
* a carrier that dies drops the bomb where it stood ("bomb_drop"); the first (lowest index)
  alive T within 0.8 m horizontally and 1.0 m vertically picks it up ("bomb_pickup"), from the
  next tick on (unless `auto_pickup` is off: a replay lets the data say who picks it up, and
  drops it where the data does, `BombRules.drop`);
* the round's end (`BombRules.outcome`): decoy_cli/sim/round_end.py.

Durations and ranges are a `RulesConfig` (decoy_cli/sim/rules_config.py), in whole ticks, so
every rule fires on an exact tick; with `bomb_enabled=False` no bomb logic runs. The zones
themselves (`SiteZones`, `BOMB_TARGET_BOXES`) live in `decoy_cli.sim.sites`. `RulesConfig` and
the zones' names are importable from here too.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from decoy_cli.compiled import njit_cached
from decoy_cli.csgo import seconds_to_ticks
from decoy_cli.sim.plant_defuse import (
    abort_defuse,
    abort_plant,
    defuse_tick,
    explode,
    plant_tick,
    within,
)
from decoy_cli.sim.round_end import round_outcome
from decoy_cli.sim.rules_config import RulesConfig
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
            events.append(abort_plant(tick, bomb, "handed_over"))
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
            events.append(abort_plant(tick, bomb, "dropped"))
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
                events += plant_tick(
                    tick, agents, bomb, wants_plant, moving, self._site_at, self.config.plant_ticks
                )
        elif bomb.status == BombStatus.DROPPED and self.config.auto_pickup:
            events += self._pickup(tick, agents, bomb)
        elif bomb.status == BombStatus.PLANTED:
            if tick >= bomb.planted_tick + self.config.bomb_ticks:
                events.append(explode(tick, bomb))
            else:
                events += defuse_tick(tick, agents, bomb, wants_defuse, moving, self.config)
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
            events.append(abort_plant(tick, bomb, "died"))
        if bomb.defuser == agent:
            events.append(abort_defuse(tick, bomb, "died"))
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
        """How the round ended at this tick, or None while it goes on (`round_outcome`)."""
        return round_outcome(tick, agents, bomb, self.config)

    # ---- internals ----------------------------------------------------------------------------

    def _pickup(self, tick: int, agents: Agents, bomb: Bomb) -> list[SimEvent]:
        cfg = self.config
        near = within(agents.position, bomb.position, cfg.pickup_range_m, cfg.pickup_vertical_m)
        takers = np.nonzero(agents.alive & (agents.side == "T") & near)[0]
        if not len(takers):
            return []
        bomb.status = BombStatus.CARRIED
        bomb.carrier = int(takers[0])
        bomb.position = agents.position[bomb.carrier].copy()
        return [
            SimEvent(tick, "bomb_pickup", bomb.carrier, data={"position": bomb.position.tolist()})
        ]


@njit_cached
def carry(bomb_position, positions, carrier):
    """A carried bomb follows its carrier: `bomb_position` (3,) takes the position of agent
    `carrier` among `positions` (N, 3), in place (-1: nobody carries it; nothing moves). The one
    place the rule is written: `BombRules.step` applies it at every tick it plays, the compiled
    stretches (`quiet_play.play_quiet`) after their glides."""
    if carrier >= 0:
        bomb_position[:] = positions[carrier]
