"""Plausible strategies as routes on the waypoint graph, built from its nav places.

A route is a list of legs: a waypoint to reach, and how long to hold there (a minimum, and an
absolute tick before which the agent does not go on: a team waits at its staging spot until the
execute) with the place to face while holding. Waypoints are drawn at random (seeded) among the
waypoints of a nav place that lie nearest a reference (the place's own centre, or another
place's: "the part of LongA nearest ARamp" is the top of long), so every round differs.

A map's strategies are a `MapPlan`. On de_dust2 they are written by hand from its places
(`DUST2_PLAN`); every other map gets the plan of `decoy_cli.synth.corridors`, built from shortest
paths on its graph. The de_dust2 plan: T strategies (`T_STRATEGIES`): A long, A short (catwalk), B
tunnels, mid to B (through mid doors and B doors), and a mid-to-A split (long, short and one player
through CT spawn). Every T walks its group's places, waits at the group's staging place until the
execute tick, then runs to a waypoint of the bomb site; the bomb carrier's last leg is a plant
waypoint inside the site's bomb-target zone. CT setups (`CT_SETUPS`): the usual 2-1-2 (long, A site,
mid, two B) and stacks on A or B; each CT walks from spawn to its role's spot and holds there facing
where the T come from, and the CTs that defend elsewhere (mid, the other site) have a rotation leg
to the edge of the attacked site on its retake side, taken when the first T reaches the site (a
call). What happens after (plant, retake, defuse, picking up a dropped bomb) is decided during the
round by the policy (decoy_cli/synth/player.py).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np

from decoy_cli.csgo import tick_at
from decoy_cli.errors import GraphError
from decoy_cli.geometry import facing_yaw
from decoy_cli.sim.rules import SiteZones
from decoy_cli.waypoints.graph import WaypointGraph

SITE_PLACES = {"A": "bombsite_a", "B": "bombsite_b"}
"""Bomb site -> the graph region (a place of `Places`) holding its waypoints."""
SPAWNS = {"T": "t_spawn", "CT": "ct_spawn"}
"""Side -> the graph region (a place of `Places`) where it spawns."""
RETAKE_FROM = {"A": "ExtendedA", "B": "BDoors"}
"""Where the CT retake of a site comes from: the place the T on the site watch."""

SPOT_SHARE = 0.3
"""Share of a place's waypoints (those nearest the reference point) a spot is drawn from."""

MIN_SPOT_NODES = 5
SPAWN_SHARE = 0.12
"""Spawn spots come from the waypoints nearest the spawn's centre: players spawn together."""

EXECUTE_S = (20.0, 45.0)
"""When the T leave their staging places, seconds after freeze-time end (uniform)."""

START_HOLD_S = (0.0, 3.0)
"""How long each player stays at its spawn first (buying, waiting), uniform."""

STAGE_JITTER_S = (0.0, 1.5)
"""Extra wait of each T at the staging place, so a group does not move as one block."""


@dataclass(frozen=True)
class Leg:
    """Reach `node`, then hold at least `hold_ticks` and until tick `until_tick`, facing the
    centre of the place `watch` (None: keep facing the way the agent came)."""

    node: int
    hold_ticks: int = 0
    until_tick: int = 0
    watch: str | None = None


@dataclass(frozen=True)
class Group:
    """T players that take the same way: through the places `via`, waiting at `stage`."""

    count: int
    via: tuple[str, ...]
    stage: str
    stage_near: str | None = None


@dataclass(frozen=True)
class TStrategy:
    """A T plan: the bomb site and the groups (their counts add up to five)."""

    name: str
    site: str
    groups: tuple[Group, ...]


_LONG = ("OutsideLong", "LongDoors", "LongA")
_SHORT = ("TopofMid", "Catwalk", "ShortStairs")

T_STRATEGIES = (
    TStrategy("A long", "A", (Group(5, _LONG, "LongDoors", "OutsideLong"),)),
    TStrategy("A short", "A", (Group(5, _SHORT, "Catwalk", "Middle"),)),
    TStrategy("B tunnels", "B", (Group(5, ("OutsideTunnel", "UpperTunnel"), "UpperTunnel"),)),
    TStrategy(
        "mid to B",
        "B",
        (Group(5, ("TopofMid", "Middle", "MidDoors", "BDoors"), "Middle", "TopofMid"),),
    ),
    TStrategy(
        "mid to A split",
        "A",
        (
            Group(2, _LONG, "LongDoors", "OutsideLong"),
            Group(2, _SHORT, "Catwalk", "Middle"),
            Group(1, ("TopofMid", "Middle", "MidDoors", "CTSpawn"), "Middle", "TopofMid"),
        ),
    ),
)


@dataclass(frozen=True)
class CtRole:
    """Where a CT holds: a spot of `place` (nearest `near`'s centre), facing `watch`; `site`
    is the bomb site the role defends (None: mid, which rotates to either)."""

    place: str
    near: str | None
    watch: str
    site: str | None


CT_ROLES = {
    "long": CtRole("LongA", "ARamp", "LongDoors", "A"),
    "A site": CtRole("BombsiteA", None, "ShortStairs", "A"),
    "short": CtRole("ExtendedA", "ShortStairs", "Catwalk", "A"),
    "mid": CtRole("MidDoors", None, "TopofMid", None),
    "B site": CtRole("BombsiteB", "UpperTunnel", "UpperTunnel", "B"),
    "B doors": CtRole("BDoors", "BombsiteB", "UpperTunnel", "B"),
}
CT_SETUPS = {
    "2-1-2": ("long", "A site", "mid", "B site", "B doors"),
    "A stack": ("long", "A site", "short", "mid", "B site"),
    "B stack": ("long", "mid", "B site", "B site", "B doors"),
}
CT_SETUP_WEIGHTS = {"2-1-2": 0.6, "A stack": 0.2, "B stack": 0.2}

TEAM_SIZE = 5


@dataclass(frozen=True)
class MapPlan:
    """The strategies of one map: T strategies, CT roles and setups (with their weights), and
    the place each site's retake comes from."""

    t_strategies: tuple[TStrategy, ...]
    ct_roles: Mapping[str, CtRole]
    ct_setups: Mapping[str, tuple[str, ...]]
    ct_setup_weights: Mapping[str, float]
    retake_from: Mapping[str, str]


DUST2_PLAN = MapPlan(T_STRATEGIES, CT_ROLES, CT_SETUPS, CT_SETUP_WEIGHTS, RETAKE_FROM)


class Places:
    """The graph's nav places and regions (`t_spawn`, `bombsite_a`, ...; plus any named sets of
    waypoints added with `add`): their waypoints, centres, and random spots near a reference."""

    def __init__(self, graph: WaypointGraph) -> None:
        self.graph = graph
        self._nodes = {
            name: np.flatnonzero(graph.node_place == k) for k, name in enumerate(graph.place_names)
        }
        self._nodes.update({name: np.asarray(nodes) for name, nodes in graph.regions.items()})
        self._centre: dict[str, np.ndarray] = {}

    def add(self, name: str, nodes: np.ndarray) -> None:
        """Name a set of waypoints, so routes can use it like a place."""
        self._nodes[name] = np.asarray(nodes, dtype=np.int64)
        self._centre.pop(name, None)

    def nodes(self, place: str) -> np.ndarray:
        """Waypoint indices of a place; a GraphError when the graph has none."""
        nodes = self._nodes.get(place)
        if nodes is None or len(nodes) == 0:
            raise GraphError(f"the waypoint graph has no waypoints in the nav place {place!r}")
        return nodes

    def centre_node(self, place: str) -> int:
        """The place's waypoint nearest the mean of its waypoints."""
        nodes = self.nodes(place)
        positions = self.graph.positions[nodes]
        mean = positions.mean(axis=0)
        return int(nodes[np.argmin(np.linalg.norm(positions - mean, axis=1))])

    def centre(self, place: str) -> np.ndarray:
        """(3,) position of the place's centre waypoint (`centre_node`)."""
        if place not in self._centre:
            self._centre[place] = self.graph.positions[self.centre_node(place)]
        return self._centre[place]

    def spots(
        self,
        place: str,
        rng: np.random.Generator,
        count: int = 1,
        near: str | None = None,
        share: float = SPOT_SHARE,
    ) -> np.ndarray:
        """`count` distinct random waypoints among the `share` of the place's waypoints nearest
        (horizontally) the centre of `near` (default: of the place itself)."""
        nodes = self.nodes(place)
        reference = self.centre(near or place)
        distance = np.linalg.norm(self.graph.positions[nodes, :2] - reference[:2], axis=1)
        keep = max(count, MIN_SPOT_NODES, round(share * len(nodes)))
        candidates = nodes[np.argsort(distance, kind="stable")[:keep]]
        return rng.choice(candidates, size=count, replace=False).astype(np.int64)

    def spot(self, place: str, rng: np.random.Generator, near: str | None = None) -> int:
        return int(self.spots(place, rng, 1, near)[0])

    def yaw_towards(self, position: np.ndarray, place: str) -> float:
        """View yaw (degrees, 0 = +x, counter-clockwise) from a position to a place's centre."""
        delta = self.centre(place) - np.asarray(position, dtype=np.float64)
        return float(facing_yaw(delta[0], delta[1]))


@dataclass(frozen=True)
class RoutePlan:
    """The scripted plan of one round: T agents 0..4, CT agents 5..9, one route each, and the
    leg each CT that defends elsewhere takes when the T reach the site (`rotations`, by agent)."""

    strategy: TStrategy
    ct_setup: str
    routes: list[list[Leg]]
    carrier: int
    plant_node: int
    rotations: dict[int, Leg]

    @property
    def site(self) -> str:
        return self.strategy.site


def plant_nodes(places: Places, zones: SiteZones, site: str) -> np.ndarray:
    """Waypoints of a site's nav place that lie inside the site's bomb-target zone."""
    nodes = places.nodes(SITE_PLACES[site])
    inside = nodes[zones.site_of(places.graph.positions[nodes]) == site]
    if len(inside) == 0:
        raise GraphError(f"no waypoint of {SITE_PLACES[site]} lies in bomb site {site}'s zone")
    return inside


def plan_round(
    places: Places, zones: SiteZones, rng: np.random.Generator, map_plan: MapPlan = DUST2_PLAN
) -> RoutePlan:
    """Draw a T strategy, a CT setup and every player's route (5 against 5)."""
    strategy = map_plan.t_strategies[int(rng.integers(len(map_plan.t_strategies)))]
    names = list(map_plan.ct_setups)
    ct_setup = str(rng.choice(names, p=[map_plan.ct_setup_weights[n] for n in names]))
    execute = tick_at(rng.uniform(*EXECUTE_S))
    site_place = SITE_PLACES[strategy.site]

    groups = [group for group in strategy.groups for _ in range(group.count)]
    order = rng.permutation(TEAM_SIZE)
    carrier = int(rng.integers(TEAM_SIZE))
    plant_node = int(rng.choice(plant_nodes(places, zones, strategy.site)))
    t_spawns = places.spots(SPAWNS["T"], rng, TEAM_SIZE, share=SPAWN_SHARE)
    routes: list[list[Leg]] = []
    for agent in range(TEAM_SIZE):
        group = groups[int(order[agent])]
        legs = [Leg(int(t_spawns[agent]), tick_at(rng.uniform(*START_HOLD_S)))]
        for place in group.via:
            if place == group.stage:
                jitter = tick_at(rng.uniform(*STAGE_JITTER_S))
                node = places.spot(place, rng, group.stage_near)
                legs.append(Leg(node, jitter, execute + jitter, watch=site_place))
            else:
                legs.append(Leg(places.spot(place, rng)))
        final = plant_node if agent == carrier else places.spot(site_place, rng)
        legs.append(Leg(final, watch=map_plan.retake_from[strategy.site]))
        routes.append(legs)

    ct_spawns = places.spots(SPAWNS["CT"], rng, TEAM_SIZE, share=SPAWN_SHARE)
    rotations = {}
    for k, role_name in enumerate(map_plan.ct_setups[ct_setup]):
        role = map_plan.ct_roles[role_name]
        hold = Leg(places.spot(role.place, rng, role.near), watch=role.watch)
        routes.append([Leg(int(ct_spawns[k]), tick_at(rng.uniform(*START_HOLD_S))), hold])
        if role.site != strategy.site:
            entry = places.spot(site_place, rng, map_plan.retake_from[strategy.site])
            rotations[TEAM_SIZE + k] = Leg(entry, watch=site_place)
    return RoutePlan(strategy, ct_setup, routes, carrier, plant_node, rotations)
