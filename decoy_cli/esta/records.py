"""The round data an ESTA file is written from, and its checks: players, events and rounds as
arrays in metres, validated before anything is written (decoy_cli/esta/writer.py writes them).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

from decoy_cli.esta.frames import Side
from decoy_cli.files import JsonObject
from decoy_cli.weapons import is_known

AWPY_HIT_GROUPS = (
    "Head",
    "Neck",
    "Chest",
    "Stomach",
    "LeftArm",
    "RightArm",
    "LeftLeg",
    "RightLeg",
    "Generic",
)
BOMB_ACTIONS = (
    "plant_begin",
    "plant_abort",
    "plant",
    "defuse_start",
    "defuse_aborted",
    "defuse",
    "explode",
)
END_REASONS = ("TargetBombed", "BombDefused", "CTWin", "TerroristsWin", "TargetSaved", "Draw")
"""awpy's round end reasons a simulated round can have."""

ROUND_TIME_S = 115.0
BOMB_TIMER_S = 40.0
FREEZE_TIME_S = 15.0
TRADE_TIME_S = 5


@dataclass(frozen=True)
class PlayerRecord:
    """One player of a round: identity, side, and what it bought.

    `inventory` lists the weapons it holds (awpy names; the C4 is added while it carries the
    bomb); `equipment_value` is its equipment at freeze-time end, `start_equipment_value` at
    the round start, `cash_spent` what it spent in this round.
    """

    name: str
    steam_id: int | None
    side: Side
    inventory: tuple[str, ...] = ()
    equipment_value: int = 0
    start_equipment_value: int = 0
    cash_spent: int = 0


@dataclass(frozen=True)
class DamageRecord:
    """One damage event; players are indices into the round's players (-1: world damage)."""

    tick: int
    attacker: int
    victim: int
    weapon: str
    hp_damage: int
    hp_damage_taken: int
    hit_group: str
    attacker_position: Sequence[float] | None  # metres, None for world damage
    victim_position: Sequence[float]
    attacker_yaw: float | None
    victim_yaw: float
    armor_damage: int = 0
    armor_damage_taken: int = 0


@dataclass(frozen=True)
class KillRecord:
    """One kill; `assister` and `traded` (the teammate avenged) are player indices or -1."""

    tick: int
    attacker: int
    victim: int
    weapon: str
    attacker_position: Sequence[float]
    victim_position: Sequence[float]
    attacker_yaw: float
    victim_yaw: float
    is_headshot: bool = False
    is_first_kill: bool = False
    assister: int = -1
    traded: int = -1


@dataclass(frozen=True)
class BombEventRecord:
    """One bomb event (awpy `bombAction`) by a player index, at a position in metres."""

    tick: int
    player: int
    action: str
    site: str
    position: Sequence[float]


@dataclass(frozen=True, eq=False)
class EstaRoundRecord:
    """One round as arrays: P players by F frames, metres and degrees; ticks are demo ticks.

    A player whose position is NaN in a frame is absent from it. Optional per-frame flags
    (`planting`, `defusing`, `in_bomb_zone`, `in_buy_zone`) default to False, `place`
    (awpy `lastPlaceName`) to "". `bomb_position` is NaN where there is no bomb.
    """

    round_num: int
    start_tick: int
    freeze_end_tick: int
    end_tick: int
    end_official_tick: int
    frame_ticks: np.ndarray  # (F,) int64
    players: list[PlayerRecord]
    position: np.ndarray  # (P, F, 3) metres
    yaw: np.ndarray  # (P, F) degrees
    hp: np.ndarray  # (P, F) int
    armor: np.ndarray  # (P, F) int
    helmet: np.ndarray  # (P, F) bool
    has_defuser: np.ndarray  # (P, F) bool
    weapon: np.ndarray  # (P, F) str
    alive: np.ndarray  # (P, F) bool
    has_bomb: np.ndarray  # (P, F) bool
    bomb_position: np.ndarray  # (F, 3) metres
    bomb_planted: np.ndarray  # (F,) bool
    bombsite: np.ndarray  # (F,) str, "A", "B" or ""
    winning_side: Side
    end_reason: str
    bomb_plant_tick: int | None = None
    damages: list[DamageRecord] = field(default_factory=list)
    kills: list[KillRecord] = field(default_factory=list)
    bomb_events: list[BombEventRecord] = field(default_factory=list)
    planting: np.ndarray | None = None
    defusing: np.ndarray | None = None
    in_bomb_zone: np.ndarray | None = None
    in_buy_zone: np.ndarray | None = None
    place: np.ndarray | None = None

    @property
    def num_frames(self) -> int:
        return len(self.frame_ticks)


@dataclass(frozen=True, eq=False)
class MatchRecord:
    """A match to write: metadata, team names by side, the rounds in order, and `provenance`
    (the top-level key that says where the data comes from, as in the real T-side files)."""

    match_id: str
    map_name: str
    tick_rate: int
    rounds: list[EstaRoundRecord]
    team_names: dict[str, str]
    provenance: JsonObject
    client_name: str = ""
    parse_rate: int = 64


def check_round(r: EstaRoundRecord) -> None:
    """Shapes, names and indices a reader would reject, caught before anything is written."""
    where = f"round {r.round_num}"
    p, f = len(r.players), r.num_frames
    expected = {
        "position": (p, f, 3),
        "yaw": (p, f),
        "hp": (p, f),
        "armor": (p, f),
        "helmet": (p, f),
        "has_defuser": (p, f),
        "weapon": (p, f),
        "alive": (p, f),
        "has_bomb": (p, f),
        "bomb_position": (f, 3),
        "bomb_planted": (f,),
        "bombsite": (f,),
    }
    for name in ("planting", "defusing", "in_bomb_zone", "in_buy_zone", "place"):
        if getattr(r, name) is not None:
            expected[name] = (p, f)
    for name, shape in expected.items():
        actual = np.shape(getattr(r, name))
        if actual != shape:
            raise ValueError(f"{where}: {name} has shape {actual}, expected {shape}")
    if np.any(np.diff(np.asarray(r.frame_ticks)) < 0):
        raise ValueError(f"{where}: frame ticks go backwards")
    if r.winning_side not in ("T", "CT"):
        raise ValueError(f"{where}: winning side {r.winning_side!r} is not T or CT")
    if r.end_reason not in END_REASONS:
        raise ValueError(f"{where}: unknown round end reason {r.end_reason!r}")
    keys = [player_key(player) for player in r.players]
    if len(set(keys)) != len(keys):
        raise ValueError(f"{where}: two players share a steamID or name")
    for player in r.players:
        if player.side not in ("T", "CT"):
            raise ValueError(f"{where}: player {player.name} has side {player.side!r}")
        for item in player.inventory:
            _check_weapon(where, item)
    for name in set(np.asarray(r.weapon).ravel().tolist()):
        _check_weapon(where, name)
    events: list[DamageRecord | KillRecord] = [*r.damages, *r.kills]
    for event in events:
        _check_weapon(where, event.weapon, allow_world=True)
        _check_player(where, r, event.victim)
        _check_player(where, r, event.attacker, allow_none=True)
    for damage in r.damages:
        if damage.hit_group not in AWPY_HIT_GROUPS:
            raise ValueError(f"{where}: unknown hit group {damage.hit_group!r}")
    for kill in r.kills:
        _check_player(where, r, kill.assister, allow_none=True)
        _check_player(where, r, kill.traded, allow_none=True)
    for bomb_event in r.bomb_events:
        if bomb_event.action not in BOMB_ACTIONS:
            raise ValueError(f"{where}: unknown bomb action {bomb_event.action!r}")
        _check_player(where, r, bomb_event.player, allow_none=True)


def _check_weapon(where: str, name: str, allow_world: bool = False) -> None:
    if not (is_known(name) or (allow_world and name == "World")):
        raise ValueError(f"{where}: unknown weapon {name!r}")


def _check_player(where: str, r: EstaRoundRecord, index: int, allow_none: bool = False) -> None:
    if not (0 <= index < len(r.players) or (allow_none and index == -1)):
        raise ValueError(f"{where}: no player {index}")


def player_key(player: PlayerRecord) -> str:
    """The reader's key: the steamID as a string, else the name."""
    return str(player.steam_id) if player.steam_id else player.name
