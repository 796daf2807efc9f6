"""Hand-made rounds of both teams in the ESTA shape of an export that records little (not real
data): per frame only name, side, position, HP and alive, as the shared CS2 rounds have them;
kills with attacker and victim; a plant's tick and site without a planter; winner and reason.

`BothTeams` builds one round from players standing on (or walking over) built-in de_dust2
waypoints at 1 frame per second, 64-tick as CS2, and writes it as a match file.
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from esta_fixtures import one_round_match

from decoy_cli.csgo import HAMMER_TO_M
from decoy_cli.waypoints.build import builtin_graph

TICK_RATE = 64
FREEZE_END = 1_000
FRAME_TICKS = 64
"""One frame per second."""


def tick_of(seconds: float) -> int:
    return round(FREEZE_END + seconds * TICK_RATE)


def site_node(region: str, k: int = 0) -> int:
    """The k-th waypoint of a region of the built-in graph ('bombsite_a', 't_spawn', ...)."""
    return int(builtin_graph().region_of(region)[k])


@dataclass
class Mate:
    name: str
    side: str
    nodes: list[int]  # one waypoint per frame (the last repeats to the end)
    dead_from: int | None = None  # first frame shown dead
    weapon: str | None = None  # written as activeWeapon when given (the export has none)

    def node(self, frame: int) -> int:
        return self.nodes[min(frame, len(self.nodes) - 1)]


@dataclass
class BothTeams:
    frames: int
    players: list[Mate]
    round_num: int = 5
    kills: list[tuple[float, str, str, str]] = field(default_factory=list)
    """(seconds, attacker, victim, weapon)."""
    plant: tuple[float, str] | None = None  # (seconds, site as the data names it)
    winner: str = "CT"
    reason: str = "TargetSaved"
    end_s: float | None = None

    def document(self) -> dict[str, Any]:
        plant_tick = None if self.plant is None else tick_of(self.plant[0])
        end = tick_of(self.end_s if self.end_s is not None else self.frames - 1)
        round_ = {
            "roundNum": self.round_num,
            "startTick": FREEZE_END - 64 * 15,
            "freezeTimeEndTick": FREEZE_END,
            "endTick": end,
            "bombPlantTick": plant_tick,
            "winningSide": self.winner,
            "roundEndReason": self.reason,
            "frames": [self._frame(j) for j in range(self.frames)],
            "kills": [self._kill(*kill) for kill in self.kills],
            "bombEvents": []
            if self.plant is None
            else [
                {
                    "tick": plant_tick,
                    "seconds": self.plant[0],
                    "clockTime": None,
                    "playerSteamID": None,
                    "playerName": None,
                    "playerX": None,
                    "playerY": None,
                    "playerZ": None,
                    "bombAction": "plant",
                    "bombSite": self.plant[1],
                }
            ],
        }
        return one_round_match("both-teams", TICK_RATE, round_, client="")

    def write(self, path: Path) -> Path:
        path.write_text(json.dumps(self.document()))
        return path

    def _hammer(self, node: int) -> tuple[float, float, float]:
        x, y, z = builtin_graph().positions[node] / HAMMER_TO_M
        return float(x), float(y), float(z)

    def _frame(self, j: int) -> dict[str, Any]:
        sides: dict[str, list[dict[str, Any]]] = {"T": [], "CT": []}
        for p in self.players:
            x, y, z = self._hammer(p.node(j))
            alive = p.dead_from is None or j < p.dead_from
            player = {
                "steamID": None,
                "name": p.name,
                "side": p.side,
                "x": x,
                "y": y,
                "z": z,
                "hp": 100 if alive else 0,
                "isAlive": alive,
            }
            if p.weapon is not None:
                player["activeWeapon"] = p.weapon if alive else ""
            sides[p.side].append(player)
        planted = self.plant is not None and j >= self.plant[0]
        return {
            "frameID": j,
            "tick": FREEZE_END + FRAME_TICKS * j,
            "seconds": float(j),
            "bombPlanted": planted,
            "bombsite": self.plant[1] if planted and self.plant else "",
            "t": {"side": "T", "players": sides["T"]},
            "ct": {"side": "CT", "players": sides["CT"]},
        }

    def _kill(self, seconds: float, attacker: str, victim: str, weapon: str) -> dict[str, Any]:
        side = {p.name: p.side for p in self.players}
        return {
            "tick": tick_of(seconds),
            "seconds": seconds,
            "attackerName": attacker,
            "attackerSide": side.get(attacker),
            "victimName": victim,
            "victimSide": side.get(victim),
            "weapon": weapon,
            "isHeadshot": False,
        }
