"""Hand-made ESTA rounds on de_dust2 that exercise the bomb: a T carrier walks into bomb site A
and plants, a CT walks to the bomb and defuses (not real data).

`BombScenario` builds one round frame by frame (2 frames per second at 128 ticks/s, positions
on the built-in waypoints, in Hammer units as the files have them) and writes it as an ESTA
match file in the awpy 1.x shape. Tests pick what the data shows: bomb events or only frames,
a drop, an interrupted plant, a defuse with or without a kit.
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from functools import cache
from pathlib import Path
from typing import Any

import numpy as np
from esta_fixtures import one_round_match

from decoy_cli.csgo import HAMMER_TO_M
from decoy_cli.sim.sites import SiteZones
from decoy_cli.waypoints.build import builtin_graph
from decoy_cli.waypoints.graph import EdgeKind

TICK_RATE = 128
FRAME_STEP = 64
FREEZE_END = 10_000
FIRST_TICK = FREEZE_END + 64
"""Frame j is at tick FIRST_TICK + 64 j, i.e. 0.5 + 0.5 j seconds on the round's clock."""


def seconds_of(tick: float) -> float:
    return (tick - FREEZE_END) / TICK_RATE


def tick_of(seconds: float) -> int:
    return round(FREEZE_END + seconds * TICK_RATE)


def frame_tick(j: int) -> int:
    return FIRST_TICK + FRAME_STEP * j


@cache
def site_a_walk() -> tuple[list[int], int]:
    """Waypoints of a straight walk (about 0.7 m a step) ending on a waypoint inside bomb site A's
    zone, and the index of the first waypoint of the walk inside the zone."""
    graph = builtin_graph()
    inside = SiteZones.from_graph(graph).site_of(graph.positions) == "A"
    for spot in np.flatnonzero(inside):
        for direction in range(8):
            run = [int(spot)]
            while len(run) < 14:
                edge = int(graph.out_edges[run[-1], direction])
                if edge < 0 or graph.edge_kind[edge] != EdgeKind.WALK:
                    break
                run.append(int(graph.edge_target[edge]))
            if len(run) == 14 and not inside[run[-1]] and inside[run[0]]:
                walk = run[::-1]  # from outside into the site
                return walk, next(k for k, node in enumerate(walk) if inside[node])
    raise AssertionError("no straight walk into site A on the built-in graph")


def hammer(node: int) -> tuple[float, float, float]:
    x, y, z = builtin_graph().positions[node] / HAMMER_TO_M
    return float(x), float(y), float(z)


@dataclass
class Player:
    name: str
    steam_id: int
    side: str
    nodes: list[int]  # waypoint per frame
    has_bomb: list[bool] = field(default_factory=list)
    kit: bool = False
    dead_from: int | None = None


@dataclass
class BombScenario:
    """One round: players with a waypoint per frame, the bomb's frames and events."""

    frames: int
    players: list[Player] = field(default_factory=list)
    planted_from: int | None = None  # first frame showing the bomb planted
    bomb_events: list[dict[str, Any]] = field(default_factory=list)
    lying: dict[int, tuple[float, float, float]] = field(default_factory=dict)
    """Frame -> where the bomb lies (Hammer) when nobody holds it."""
    plant_tick: int | None = None  # bombPlantTick (default: the first planted frame's tick)

    def event(self, tick: int, action: str, player: Player, site: str = "A") -> None:
        x, y, z = hammer(player.nodes[min(self._frame_at(tick), self.frames - 1)])
        self.bomb_events.append(
            {
                "tick": tick,
                "seconds": seconds_of(tick),
                "clockTime": "",
                "playerSteamID": player.steam_id,
                "playerName": player.name,
                "playerTeam": "Team A" if player.side == "T" else "Team B",
                "playerX": x,
                "playerY": y,
                "playerZ": z,
                "bombAction": action,
                "bombSite": site,
            }
        )

    @staticmethod
    def _frame_at(tick: int) -> int:
        return max(0, (tick - FIRST_TICK) // FRAME_STEP)

    def document(self) -> dict[str, Any]:
        frames = [self._frame(j) for j in range(self.frames)]
        plant_tick = self.plant_tick
        if plant_tick is None and self.planted_from is not None:
            plant_tick = frame_tick(self.planted_from)
        round_ = {
            "roundNum": 1,
            "startTick": FIRST_TICK - 640,
            "freezeTimeEndTick": FREEZE_END,
            "endTick": frame_tick(self.frames - 1),
            "bombPlantTick": plant_tick,
            "winningSide": None,
            "roundEndReason": None,
            "frames": frames,
            "bombEvents": self.bomb_events,
        }
        return one_round_match("bomb-scenario", TICK_RATE, round_)

    def write(self, path: Path) -> Path:
        path.write_text(json.dumps(self.document()))
        return path

    def _frame(self, j: int) -> dict[str, Any]:
        sides: dict[str, list[dict[str, Any]]] = {"T": [], "CT": []}
        carrier_at = None
        for p in self.players:
            x, y, z = hammer(p.nodes[j])
            alive = p.dead_from is None or j < p.dead_from
            bomb = bool(p.has_bomb[j]) if j < len(p.has_bomb) else False
            if bomb and alive:
                carrier_at = (x, y, z)
            sides[p.side].append(
                {
                    "steamID": p.steam_id,
                    "name": p.name,
                    "side": p.side,
                    "x": x,
                    "y": y,
                    "z": z,
                    "viewX": 90.0,
                    "viewY": 0.0,
                    "hp": 100 if alive else 0,
                    "armor": 100,
                    "hasHelmet": True,
                    "hasDefuse": p.kit,
                    "hasBomb": bomb and alive,
                    "isAlive": alive,
                    "activeWeapon": "AK-47" if p.side == "T" else "M4A4",
                }
            )
        planted = self.planted_from is not None and j >= self.planted_from
        if carrier_at is not None:
            bomb = carrier_at
        elif j in self.lying:
            bomb = self.lying[j]
        else:
            bomb = self._planted_at() if planted else (0.0, 0.0, 0.0)
        return {
            "tick": frame_tick(j),
            "seconds": seconds_of(frame_tick(j)),
            "bombPlanted": planted,
            "bombsite": "",
            "bomb": {"x": bomb[0], "y": bomb[1], "z": bomb[2]},
            "t": {"side": "T", "players": sides["T"]},
            "ct": {"side": "CT", "players": sides["CT"]},
        }

    def _planted_at(self) -> tuple[float, float, float]:
        """Where the bomb lies once planted: where its last carrier stood."""
        for j in range((self.planted_from or 0), -1, -1):
            for p in self.players:
                if j < len(p.has_bomb) and p.has_bomb[j]:
                    return hammer(p.nodes[min(j + 1, self.frames - 1)])
        return (0.0, 0.0, 0.0)
