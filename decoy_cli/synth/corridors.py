"""Strategies for any map, from shortest paths on its waypoint graph (`corridor_plan`).

A map without hand-written strategies still has spawns and bomb sites. The ways between them are
the graph's shortest paths, and a corridor is the waypoints within `CORRIDOR_M` of a stretch of
such a path, named so routes can use it like a nav place:

* `T approach A` / `T approach B`: the stretch of the path from the T spawn to the site between
  `T_STAGE` of its length (where a T group waits for the execute);
* `CT approach A` / `CT approach B`: the stretch of the path from the CT spawn to the site just
  before it (`CT_ENTRY`), where a retake comes from;
* `mid`: the middle stretch of the path between the two sites (`MID`), where one CT holds and
  from where a split T group enters.

The T take a site directly or split (three by the approach, two through mid); the CT play 2-1-2
or stack a site, holding on the site near the T approach and facing it. Nothing here knows a map:
the same code gives every map its plan, and de_dust2's hand-written plan stays its own.
"""

from __future__ import annotations

import numpy as np
from scipy.spatial import cKDTree

from decoy_cli.errors import GraphError
from decoy_cli.synth.routes import (
    SITE_PLACES,
    SPAWNS,
    CtRole,
    Group,
    MapPlan,
    Places,
    TStrategy,
)

CORRIDOR_M = 2.0
"""How far from the path a corridor's waypoints may lie (a few lattice steps)."""

T_STAGE = (0.55, 0.8)
"""The stretch of the T spawn -> site path (shares of its length) where the T stage."""

CT_ENTRY = (0.7, 0.95)
"""The stretch of the CT spawn -> site path a retake comes in by."""

MID = (0.35, 0.65)
"""The stretch of the site A -> site B path that is "mid"."""


def _stretch(places: Places, source: str, target: str, share: tuple[float, float]) -> np.ndarray:
    """Waypoints within CORRIDOR_M of the stretch [share] of the shortest path between the
    centres of two places."""
    graph = places.graph
    start, end = places.centre_node(source), places.centre_node(target)
    path = graph.shortest_path(start, end)
    if len(path) < 2:
        raise GraphError(f"no path on the waypoint graph from {source} to {target}")
    steps = np.linalg.norm(np.diff(graph.positions[path], axis=0), axis=1)
    along = np.concatenate([[0.0], np.cumsum(steps)]) / max(float(steps.sum()), 1e-9)
    inside = np.asarray(path)[(along >= share[0]) & (along <= share[1])]
    if len(inside) == 0:  # a very short path: its middle node
        inside = np.asarray(path[len(path) // 2 : len(path) // 2 + 1])
    near = cKDTree(graph.positions).query_ball_point(graph.positions[inside], r=CORRIDOR_M)
    return np.unique(np.concatenate([inside, *map(np.asarray, near)]).astype(np.int64))


def corridor_plan(places: Places) -> MapPlan:
    """Add the corridors to `places` and return the map's plan (see the module docstring)."""
    for site, region in SITE_PLACES.items():
        places.add(f"T approach {site}", _stretch(places, SPAWNS["T"], region, T_STAGE))
        places.add(f"CT approach {site}", _stretch(places, SPAWNS["CT"], region, CT_ENTRY))
    places.add("mid", _stretch(places, SITE_PLACES["A"], SITE_PLACES["B"], MID))

    strategies = []
    for site in SITE_PLACES:
        approach = f"T approach {site}"
        strategies.append(TStrategy(f"{site} execute", site, (Group(5, (approach,), approach),)))
        strategies.append(
            TStrategy(
                f"{site} split",
                site,
                (Group(3, (approach,), approach), Group(2, ("mid",), "mid", SPAWNS["T"])),
            )
        )
    roles = {
        f"{site} site": CtRole(region, f"T approach {site}", f"T approach {site}", site)
        for site, region in SITE_PLACES.items()
    }
    roles["mid"] = CtRole("mid", None, SPAWNS["T"], None)
    setups = {
        "2-1-2": ("A site", "A site", "mid", "B site", "B site"),
        "A stack": ("A site", "A site", "A site", "mid", "B site"),
        "B stack": ("A site", "mid", "B site", "B site", "B site"),
    }
    weights = {"2-1-2": 0.6, "A stack": 0.2, "B stack": 0.2}
    retake = {site: f"CT approach {site}" for site in SITE_PLACES}
    return MapPlan(tuple(strategies), roles, setups, weights, retake)
