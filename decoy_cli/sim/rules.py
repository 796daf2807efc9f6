"""Bomb and round rules of a CS:GO round, advanced tick by tick by the engine (pure numpy).

Durations are whole tick counts (`RulesConfig`), so every rule fires on an exact tick:

* plant: the carrier, alive, inside a bomb-site zone and not moving, wants to plant at tick t0
  ("plant_begin"); the plant completes at t0 + plant_ticks (3.2 s = 192 ticks at 60 Hz) if at
  every tick in between it is still alive, still, in the zone and still wants to; otherwise
  "plant_abort" (data "reason": died, stopped, moved or left_zone);
* detonation: at planted_tick + bomb_ticks (40 s = 2400 ticks), checked before any defuse
  progress of that tick, so a defuse must end strictly before the detonation tick;
* defuse: an alive CT that wants to, stands still and is within 1.5 m horizontally and 1.0 m
  vertically of the planted bomb starts at t0 ("defuse_start"; with several candidates the lowest
  agent index, one defuser at a time) and ends at t0 + defuse ticks (10 s = 600 ticks, 5 s = 300
  with a kit); CS:GO cancels a defuse when the defuser moves, so moving aborts it, like dying,
  leaving the range or no longer wanting to ("defuse_aborted");
* a carrier that dies drops the bomb where it stood ("bomb_drop"); the first (lowest index)
  alive T within 0.8 m horizontally and 1.0 m vertically picks it up ("bomb_pickup"), from the
  next tick on.

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

Bomb-site zones (`SiteZones`): on de_dust2 the zones are the game's bomb-target volumes measured
from real rounds (see `BOMB_TARGET_BOXES`); the nav places BombsiteA/B that name the graph's site
regions cover about twice that area. Elsewhere a zone is the space within 0.75 m horizontally
and 1.5 m vertically of a site waypoint.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from itertools import chain

import numpy as np
from scipy.spatial import cKDTree

from decoy_cli.csgo import TICK_RATE, seconds_to_ticks
from decoy_cli.sim.state import Agents, Bomb, BombStatus, RoundOutcome, SimEvent
from decoy_cli.waypoints.graph import WaypointGraph

Box = tuple[tuple[float, ...], tuple[float, ...]]
"""An axis-aligned box: (low x, y, z), (high x, y, z), metres."""

SITE_REGIONS = {"A": "bombsite_a", "B": "bombsite_b"}
"""Bomb site name -> graph region holding its waypoints."""

ZONE_HORIZONTAL_M = 0.75
"""How far from a site waypoint, horizontally, a site zone reaches. Just over the waypoint
lattice spacing (0.70 m), so the zone has no holes between waypoints."""

ZONE_VERTICAL_M = 1.5
"""How far above or below a site waypoint a site zone reaches (a jump, stairs, a ramp)."""

_MEASURED_BOMB_TARGETS: dict[str, dict[str, Box]] = {
    "de_dust2": {
        "A": ((18.29, 44.33, 1.80), (24.08, 50.29, 3.39)),
        "B": ((-33.15, 47.24, 0.00), (-25.94, 54.41, 1.82)),
    },
}
# The bounds of every position where the bomb carrier had awpy's `isInBombZone` set (the game's
# func_bomb_target trigger; the flag is only ever set for the carrier), over the 385 real T-side
# rounds of ../shared/data/esta_dust2_tside (44,423 carrier frames, 1,854 in a zone), rounded
# outward to the centimetre. 1,854 of the 1,856 carrier frames inside those bounds are in a zone:
# the volumes are boxes. Boxes fitted on 8 of the 15 matches and tested on the other 7 (20 random
# splits) agree with the game's flag at precision 0.990 and recall 0.991 with a 0.1 m margin
# (0.999 / 0.976 without); the waypoint zones of the nav-place site regions reach recall 0.992
# but precision 0.576 (they cover twice the area). All 197 real plant positions of those rounds
# lie in the boxes (195 in the region zones), and the 18 plants of the independent OG-NaVi match
# (../shared/data/esta_dust2_events) all lie in the box of the site the game logged.

BOX_MARGIN_M = 0.1
"""Added on every side of a measured box: the data bounds where players stood, not the trigger."""

BOMB_TARGET_BOXES: dict[str, dict[str, Box]] = {
    map_name: {
        site: (
            tuple(v - BOX_MARGIN_M for v in low),
            tuple(v + BOX_MARGIN_M for v in high),
        )
        for site, (low, high) in sites.items()
    }
    for map_name, sites in _MEASURED_BOMB_TARGETS.items()
}
"""Bomb-site zones of the maps whose bomb-target volumes are known, by map name, metres."""


class SiteZones:
    """Bomb-site zones: a point is in a site if it lies inside one of the site's boxes or within
    `horizontal_m` horizontally and `vertical_m` vertically of one of its waypoints.

    Sites are tried in sorted name order; the first that holds a point names it.
    """

    def __init__(
        self,
        nodes: Mapping[str, np.ndarray] | None = None,
        boxes: Mapping[str, Box] | None = None,
        horizontal_m: float = ZONE_HORIZONTAL_M,
        vertical_m: float = ZONE_VERTICAL_M,
    ) -> None:
        nodes = dict(nodes or {})
        boxes = dict(boxes or {})
        self.names: list[str] = sorted(set(nodes) | set(boxes))
        if not self.names or any(not isinstance(n, str) or not n for n in self.names):
            raise ValueError("bomb-site zones need at least one site, named by a non-empty str")
        if not (horizontal_m > 0 and vertical_m > 0):
            raise ValueError("bomb-site zone ranges must be positive")
        self.horizontal_m = float(horizontal_m)
        self.vertical_m = float(vertical_m)
        index = {name: k for k, name in enumerate(self.names)}

        low, high, box_site = [], [], []
        for name, (lo, hi) in boxes.items():
            lo_arr = np.asarray(lo, dtype=np.float64)
            hi_arr = np.asarray(hi, dtype=np.float64)
            if lo_arr.shape != (3,) or hi_arr.shape != (3,) or not np.all(lo_arr <= hi_arr):
                raise ValueError(f"site {name!r}: a box is (low xyz, high xyz) with low <= high")
            low.append(lo_arr)
            high.append(hi_arr)
            box_site.append(index[name])
        self._box_low = np.asarray(low, dtype=np.float64).reshape(-1, 3)
        self._box_high = np.asarray(high, dtype=np.float64).reshape(-1, 3)
        self._box_site = np.asarray(box_site, dtype=np.int64)

        positions, node_site = [], []
        for name, pos in nodes.items():
            arr = np.asarray(pos, dtype=np.float64)
            if arr.ndim != 2 or arr.shape[1] != 3 or not np.all(np.isfinite(arr)):
                raise ValueError(f"site {name!r}: waypoints must be finite, shape (K, 3)")
            positions.append(arr)
            node_site.append(np.full(len(arr), index[name], dtype=np.int64))
        self._node_z = np.concatenate(positions)[:, 2] if positions else np.empty(0)
        self._node_site = np.concatenate(node_site) if node_site else np.empty(0, np.int64)
        self._tree = cKDTree(np.concatenate(positions)[:, :2]) if len(self._node_z) else None
        self._labels = np.asarray([*self.names, ""])

    @classmethod
    def from_graph(
        cls,
        graph: WaypointGraph,
        boxes: Mapping[str, Box] | None = None,
        horizontal_m: float = ZONE_HORIZONTAL_M,
        vertical_m: float = ZONE_VERTICAL_M,
    ) -> SiteZones:
        """Zones of sites A and B: the given boxes (default: the measured bomb-target boxes of
        the graph's map, if known); a site without a box uses the waypoints of its region
        (`bombsite_a`, `bombsite_b`). Pass `boxes={}` to use the regions on every map."""
        if boxes is None:
            boxes = BOMB_TARGET_BOXES.get(str(graph.meta.get("map", "")), {})
        nodes = {
            site: graph.positions[graph.region_of(region)]
            for site, region in SITE_REGIONS.items()
            if site not in boxes
        }
        return cls(nodes=nodes, boxes=boxes, horizontal_m=horizontal_m, vertical_m=vertical_m)

    def site_of(self, points: np.ndarray) -> np.ndarray:
        """Site name of every point of an (M, 3) array ("" outside every zone or not finite)."""
        pts = np.atleast_2d(np.asarray(points, dtype=np.float64))
        if pts.ndim != 2 or pts.shape[1] != 3:
            raise ValueError(f"site_of() wants points of shape (M, 3), got {pts.shape}")
        none = len(self.names)
        inside = np.all(
            (pts[:, None, :] >= self._box_low[None]) & (pts[:, None, :] <= self._box_high[None]),
            axis=2,
        )
        best = np.where(inside, self._box_site[None, :], none).min(axis=1, initial=none)
        if self._tree is not None:
            rows = np.nonzero(np.all(np.isfinite(pts), axis=1))[0]
            hits = self._tree.query_ball_point(pts[rows, :2], r=self.horizontal_m)
            counts = np.fromiter(map(len, hits), dtype=np.int64, count=len(hits))
            cols = np.fromiter(chain.from_iterable(hits), dtype=np.int64, count=int(counts.sum()))
            rows = np.repeat(rows, counts)
            near = np.abs(self._node_z[cols] - pts[rows, 2]) <= self.vertical_m
            np.minimum.at(best, rows[near], self._node_site[cols[near]])
        return self._labels[best]


@dataclass(frozen=True)
class RulesConfig:
    """Durations (seconds) and ranges (metres) of the bomb and round rules.

    The durations are converted once to whole tick counts (`round_ticks`, `plant_ticks`,
    `bomb_ticks`, `defuse_ticks`, `defuse_kit_ticks`) by `seconds_to_ticks` (rounded up).
    """

    tick_rate: int = TICK_RATE
    round_time_s: float = 115.0
    plant_s: float = 3.2
    bomb_timer_s: float = 40.0
    defuse_s: float = 10.0
    defuse_kit_s: float = 5.0
    defuse_range_m: float = 1.5  # horizontal; CS:GO's use range is about 62 u (1.2 m)
    defuse_vertical_m: float = 1.0
    pickup_range_m: float = 0.8  # horizontal
    pickup_vertical_m: float = 1.0
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
                bomb.position = agents.position[bomb.carrier].copy()
                events += self._plant(tick, agents, bomb, wants_plant, moving)
        elif bomb.status == BombStatus.DROPPED:
            events += self._pickup(tick, agents, bomb)
        elif bomb.status == BombStatus.PLANTED:
            if tick >= bomb.planted_tick + self.config.bomb_ticks:
                events.append(self._explode(tick, bomb))
            else:
                events += self._defuse(tick, agents, bomb, wants_defuse, moving)
        return events

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
        if bomb.planter != carrier and not wants_plant[carrier]:
            return []
        site = str(self.zones.site_of(agents.position[carrier])[0])
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
            return [SimEvent(tick, "plant", carrier, data={"site": site})]
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


def _first_true(*checks: tuple[str, bool]) -> str:
    """The name of the first check that holds ("" if none does): why a plant or defuse stops."""
    return next((name for name, failed in checks if failed), "")
