"""Write ESTA match files (awpy 1.x JSON, `.json.xz`) from round data in metres.

The inverse of the reader (decoy_cli/esta/reader.py) for the keys it reads, plus the rest of
the awpy 1.x key set that real files carry, so a written file looks like a real one to any
awpy-based tool: `MatchRecord` holds the rounds as arrays (P players by F frames, metres,
degrees, demo ticks) and event records; `match_document` turns it into the JSON document and
`write_match` writes it, xz-compressed for `.json.xz`, atomically.

Units are converted here, once: metres to Hammer units, stored as float32 values (what awpy
writes), printed in their shortest form so the file stays small. Values the data does not hold
(grenades, cash, ammunition) are zeros, empty lists or nulls, as awpy writes for them.
Derived per frame: `seconds` and `clockTime` from the tick, velocities from consecutive frames,
eye positions 64 u above the feet (standing), team equipment values and alive counts, buy types
from team equipment (awpy's "hltv" style thresholds, checked against the real files: Full Eco
below 5,000, Semi Eco below 10,000, Semi Buy below 20,000, else Full Buy) and the scores before
and after each round from the winners. Output is deterministic: the same record gives the same
bytes.
"""

from __future__ import annotations

import lzma
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import msgspec
import numpy as np

from decoy_cli.csgo import EYE_HEIGHT_M, HAMMER_TO_M
from decoy_cli.errors import OutputError
from decoy_cli.esta.frames import Side
from decoy_cli.files import write_atomic
from decoy_cli.weapons import WEAPONS, is_known

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
XZ_PRESET = 6
"""xz preset: the default. Measured on an 8-round sample (14.3 MB of JSON): preset 6 gives 165 KB
in 2.0 s, 9 the same size, extreme 151 KB in 4.7-5.9 s."""

_BUY_TYPES = ((5_000, "Full Eco"), (10_000, "Semi Eco"), (20_000, "Semi Buy"))
_ENCODER = msgspec.json.Encoder()


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
    provenance: dict[str, Any]
    client_name: str = ""
    parse_rate: int = 64


def write_match(match: MatchRecord, path: str | Path) -> Path:
    """Write the match to `path` (`.json.xz` compressed, `.json` plain), atomically."""
    path = Path(path)
    if not path.name.endswith((".json.xz", ".json")):
        raise OutputError(f"cannot write {path}: a match file name ends in .json.xz or .json")
    data = encode_match(match)
    if path.name.endswith(".xz"):
        data = lzma.compress(data, preset=XZ_PRESET)
    return write_atomic(path, data)


def encode_match(match: MatchRecord) -> bytes:
    """The match as JSON bytes (UTF-8, keys in awpy order)."""
    return _ENCODER.encode(match_document(match))


def match_document(match: MatchRecord) -> dict[str, Any]:
    """The awpy 1.x JSON document of a match (plain dicts, lists and numbers)."""
    for side in ("T", "CT"):
        if side not in match.team_names:
            raise ValueError(f"team_names needs a name for side {side}")
    nums = [r.round_num for r in match.rounds]
    if len(set(nums)) != len(nums):
        raise ValueError("round numbers must be unique")
    scores = {"T": 0, "CT": 0}
    spent_total: dict[str, int] = {}
    global_frame = 0
    rounds = []
    for record in match.rounds:
        _check_round(record)
        document = _round_document(match, record, dict(scores), spent_total, global_frame)
        rounds.append(document)
        global_frame += record.num_frames
        scores[record.winning_side] += 1
    first = match.rounds[0].start_tick if match.rounds else 0
    last = match.rounds[-1].end_official_tick if match.rounds else 0
    return {
        "matchID": match.match_id,
        "clientName": match.client_name,
        "mapName": match.map_name,
        "tickRate": match.tick_rate,
        "playbackTicks": last,
        "parserParameters": {
            "parseRate": match.parse_rate,
            "parseFrames": True,
            "parseKillFrames": False,
            "tradeTime": TRADE_TIME_S,
            "roundBuyStyle": "hltv",
            "damagesRolledUp": False,
        },
        "serverVars": {
            "roundTime": int(ROUND_TIME_S),
            "roundTimeDefuse": int(ROUND_TIME_S),
            "freezeTime": int(FREEZE_TIME_S),
            "bombTimer": int(BOMB_TIMER_S),
            "maxRounds": 30,
        },
        "matchPhases": {
            "announcementMatchStarted": [first],
            "roundStarted": [r.start_tick for r in match.rounds],
            "roundFreezetimeEnded": [r.freeze_end_tick for r in match.rounds],
            "roundEnded": [r.end_tick for r in match.rounds],
            "roundEndedOfficial": [r.end_official_tick for r in match.rounds],
        },
        "playerConnections": [],
        "provenance": match.provenance,
        "gameRounds": rounds,
    }


# ---- checks ------------------------------------------------------------------------------------


def _check_round(r: EstaRoundRecord) -> None:
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
    keys = [_key(player) for player in r.players]
    if len(set(keys)) != len(keys):
        raise ValueError(f"{where}: two players share a steamID or name")
    for player in r.players:
        if player.side not in ("T", "CT"):
            raise ValueError(f"{where}: player {player.name} has side {player.side!r}")
        for item in player.inventory:
            _check_weapon(where, item)
    for name in set(np.asarray(r.weapon).ravel().tolist()):
        _check_weapon(where, name)
    for event in (*r.damages, *r.kills):
        _check_weapon(where, event.weapon, allow_world=True)
        _check_player(where, r, event.victim)
        _check_player(where, r, event.attacker, allow_none=True)
    for damage in r.damages:
        if damage.hit_group not in AWPY_HIT_GROUPS:
            raise ValueError(f"{where}: unknown hit group {damage.hit_group!r}")
    for kill in r.kills:
        _check_player(where, r, kill.assister, allow_none=True)
        _check_player(where, r, kill.traded, allow_none=True)
    for event in r.bomb_events:
        if event.action not in BOMB_ACTIONS:
            raise ValueError(f"{where}: unknown bomb action {event.action!r}")
        _check_player(where, r, event.player, allow_none=True)


def _check_weapon(where: str, name: str, allow_world: bool = False) -> None:
    if not (is_known(name) or (allow_world and name == "World")):
        raise ValueError(f"{where}: unknown weapon {name!r}")


def _check_player(where: str, r: EstaRoundRecord, index: int, allow_none: bool = False) -> None:
    if not (0 <= index < len(r.players) or (allow_none and index == -1)):
        raise ValueError(f"{where}: no player {index}")


def _key(player: PlayerRecord) -> str:
    """The reader's key: the steamID as a string, else the name."""
    return str(player.steam_id) if player.steam_id else player.name


# ---- values ------------------------------------------------------------------------------------


def _hammer(values: np.ndarray) -> np.ndarray:
    """Metres to Hammer units, as float32 (what awpy stores); NaN stays NaN."""
    return (np.asarray(values, dtype=np.float64) / HAMMER_TO_M).astype(np.float32)


def _floats(values: np.ndarray) -> list[Any]:
    """float32 values as Python floats printed in their shortest float32 form; NaN -> None."""
    flat = np.asarray(values, dtype=np.float32).ravel()
    text = flat.astype(str)
    out: list[Any] = [None if s == "nan" else float(s) for s in text]
    return out


def _buy_type(value: int) -> str:
    for limit, name in _BUY_TYPES:
        if value < limit:
            return name
    return "Full Buy"


def _clock(seconds: float, planted_seconds: float | None) -> str:
    """awpy's `clockTime`: the round clock counting down, the bomb timer after a plant."""
    if planted_seconds is not None and seconds >= planted_seconds:
        left = BOMB_TIMER_S - (seconds - planted_seconds)
    else:
        left = ROUND_TIME_S - seconds
    whole = max(0, int(np.ceil(round(left, 6))))
    return f"{whole // 60:02d}:{whole % 60:02d}"


def _weapon_class(name: str) -> str | None:
    return WEAPONS[name][0] if name in WEAPONS else None


# ---- documents ---------------------------------------------------------------------------------


def _round_document(
    match: MatchRecord,
    r: EstaRoundRecord,
    scores: dict[str, int],
    spent_total: dict[str, int],
    global_frame: int,
) -> dict[str, Any]:
    rate = match.tick_rate
    teams = match.team_names
    loser = "CT" if r.winning_side == "T" else "T"
    end_scores = dict(scores)
    end_scores[r.winning_side] += 1
    side_players = {s: [p for p in r.players if p.side == s] for s in ("T", "CT")}
    freeze_value = {s: sum(p.equipment_value for p in side_players[s]) for s in ("T", "CT")}
    start_value = {s: sum(p.start_equipment_value for p in side_players[s]) for s in ("T", "CT")}
    spent = {s: sum(p.cash_spent for p in side_players[s]) for s in ("T", "CT")}
    for player in r.players:
        key = _key(player)
        spent_total[key] = spent_total.get(key, 0) + player.cash_spent
    plant_s = None if r.bomb_plant_tick is None else (r.bomb_plant_tick - r.freeze_end_tick) / rate
    context = _EventContext(match, r, plant_s)
    return {
        "roundNum": r.round_num,
        "isWarmup": False,
        "startTick": r.start_tick,
        "freezeTimeEndTick": r.freeze_end_tick,
        "endTick": r.end_tick,
        "endOfficialTick": r.end_official_tick,
        "bombPlantTick": r.bomb_plant_tick,
        "tScore": scores["T"],
        "ctScore": scores["CT"],
        "endTScore": end_scores["T"],
        "endCTScore": end_scores["CT"],
        "ctTeam": teams["CT"],
        "tTeam": teams["T"],
        "winningSide": r.winning_side,
        "winningTeam": teams[r.winning_side],
        "losingTeam": teams[loser],
        "roundEndReason": r.end_reason,
        "ctFreezeTimeEndEqVal": freeze_value["CT"],
        "ctRoundStartEqVal": start_value["CT"],
        "ctRoundSpendMoney": spent["CT"],
        "ctBuyType": _buy_type(freeze_value["CT"]),
        "tFreezeTimeEndEqVal": freeze_value["T"],
        "tRoundStartEqVal": start_value["T"],
        "tRoundSpendMoney": spent["T"],
        "tBuyType": _buy_type(freeze_value["T"]),
        "ctSide": _side_roster(teams["CT"], side_players["CT"]),
        "tSide": _side_roster(teams["T"], side_players["T"]),
        "kills": [context.kill(k) for k in r.kills],
        "damages": [context.damage(d) for d in r.damages],
        "grenades": [],
        "bombEvents": [context.bomb_event(b) for b in r.bomb_events],
        "weaponFires": [],
        "flashes": [],
        "frames": _frames(match, r, plant_s, spent_total, global_frame),
    }


def _side_roster(team: str, players: list[PlayerRecord]) -> dict[str, Any]:
    return {
        "teamName": team,
        "players": [{"playerName": p.name, "steamID": p.steam_id} for p in players],
    }


class _EventContext:
    """Turns event records into awpy event dicts (identity, Hammer positions, time)."""

    def __init__(self, match: MatchRecord, r: EstaRoundRecord, plant_s: float | None) -> None:
        self.rate = match.tick_rate
        self.teams = match.team_names
        self.r = r
        self.plant_s = plant_s

    def _time(self, tick: int) -> dict[str, Any]:
        seconds = (tick - self.r.freeze_end_tick) / self.rate
        return {"tick": tick, "seconds": seconds, "clockTime": _clock(seconds, self.plant_s)}

    def _who(self, role: str, index: int) -> dict[str, Any]:
        if index < 0:
            return {f"{role}{k}": None for k in ("SteamID", "Name", "Team", "Side")}
        player = self.r.players[index]
        return {
            f"{role}SteamID": player.steam_id,
            f"{role}Name": player.name,
            f"{role}Team": self.teams[player.side],
            f"{role}Side": player.side,
        }

    @staticmethod
    def _where(role: str, position: Sequence[float] | None, yaw: float | None) -> dict[str, Any]:
        if position is None:
            x = y = z = view = None
        else:
            x, y, z = _floats(_hammer(np.asarray(position)))
            view = None if yaw is None else _floats(np.array([yaw]))[0]
        return {
            f"{role}X": x,
            f"{role}Y": y,
            f"{role}Z": z,
            f"{role}ViewX": view,
            f"{role}ViewY": None if view is None else 0.0,
        }

    @staticmethod
    def _distance(a: Sequence[float] | None, b: Sequence[float]) -> float | None:
        if a is None:
            return None
        metres = float(np.linalg.norm(np.asarray(a, float) - np.asarray(b, float)))
        return _floats(np.array([metres / HAMMER_TO_M]))[0]

    def damage(self, d: DamageRecord) -> dict[str, Any]:
        attacker = self._who("attacker", d.attacker)
        victim = self._who("victim", d.victim)
        return {
            **self._time(d.tick),
            **attacker,
            **self._where("attacker", d.attacker_position, d.attacker_yaw),
            "attackerStrafe": None if d.attacker < 0 else False,
            **victim,
            **self._where("victim", d.victim_position, d.victim_yaw),
            "weapon": d.weapon,
            "weaponClass": _weapon_class(d.weapon),
            "hpDamage": d.hp_damage,
            "hpDamageTaken": d.hp_damage_taken,
            "armorDamage": d.armor_damage,
            "armorDamageTaken": d.armor_damage_taken,
            "hitGroup": d.hit_group,
            "isFriendlyFire": d.attacker >= 0
            and self.r.players[d.attacker].side == self.r.players[d.victim].side,
            "distance": self._distance(d.attacker_position, d.victim_position),
            "zoomLevel": 0,
        }

    def kill(self, k: KillRecord) -> dict[str, Any]:
        players = self.r.players
        same_side = k.attacker >= 0 and players[k.attacker].side == players[k.victim].side
        traded = self._who("playerTraded", k.traded)
        return {
            **self._time(k.tick),
            **self._who("attacker", k.attacker),
            **self._where("attacker", k.attacker_position, k.attacker_yaw),
            **self._who("victim", k.victim),
            **self._where("victim", k.victim_position, k.victim_yaw),
            **self._who("assister", k.assister),
            "isSuicide": k.attacker == k.victim,
            "isTeamkill": same_side and k.attacker != k.victim,
            "isWallbang": False,
            "penetratedObjects": 0,
            "isFirstKill": k.is_first_kill,
            "isHeadshot": k.is_headshot,
            "victimBlinded": False,
            "attackerBlinded": False,
            **self._who("flashThrower", -1),
            "noScope": False,
            "thruSmoke": False,
            "distance": self._distance(k.attacker_position, k.victim_position),
            "isTrade": k.traded >= 0,
            "playerTradedName": traded["playerTradedName"],
            "playerTradedTeam": traded["playerTradedTeam"],
            "playerTradedSteamID": traded["playerTradedSteamID"],
            "weapon": k.weapon,
            "weaponClass": _weapon_class(k.weapon),
        }

    def bomb_event(self, b: BombEventRecord) -> dict[str, Any]:
        who = self._who("player", b.player)
        x, y, z = _floats(_hammer(np.asarray(b.position)))
        return {
            **self._time(b.tick),
            "playerSteamID": who["playerSteamID"],
            "playerName": who["playerName"],
            "playerTeam": who["playerTeam"],
            "playerX": x,
            "playerY": y,
            "playerZ": z,
            "bombAction": b.action,
            "bombSite": b.site,
        }


def _frames(
    match: MatchRecord,
    r: EstaRoundRecord,
    plant_s: float | None,
    spent_total: dict[str, int],
    global_frame: int,
) -> list[dict[str, Any]]:
    """Every frame of a round, both sides, with the full awpy player state."""
    rate = match.tick_rate
    ticks = np.asarray(r.frame_ticks, dtype=np.int64)
    p, f = len(r.players), len(ticks)
    position = np.asarray(r.position, dtype=np.float64)
    present = np.all(np.isfinite(position), axis=2)
    hammer = _hammer(position)
    # velocity from the previous frame (u/s); 0 in the first frame and next to an absence
    velocity = np.zeros((p, f, 3), dtype=np.float32)
    if f > 1:
        dt = np.diff(ticks) / rate
        step = np.diff(hammer.astype(np.float64), axis=1) / np.where(dt > 0, dt, np.inf)[:, None]
        moving = present[:, 1:] & present[:, :-1] & np.asarray(r.alive)[:, 1:]
        velocity[:, 1:] = np.where(moving[..., None], step, 0.0).astype(np.float32)
    eye_z = _hammer(position[..., 2] + EYE_HEIGHT_M)
    columns = {
        "x": _floats(hammer[..., 0]),
        "y": _floats(hammer[..., 1]),
        "z": _floats(hammer[..., 2]),
        "eyeZ": _floats(eye_z),
        "vx": _floats(velocity[..., 0]),
        "vy": _floats(velocity[..., 1]),
        "vz": _floats(velocity[..., 2]),
        "yaw": _floats(np.asarray(r.yaw)),
    }
    flags = {
        name: np.zeros((p, f), bool) if getattr(r, name) is None else np.asarray(getattr(r, name))
        for name in ("planting", "defusing", "in_bomb_zone", "in_buy_zone")
    }
    place = np.full((p, f), "", dtype=object) if r.place is None else np.asarray(r.place)
    bomb = _floats(_hammer(np.asarray(r.bomb_position)))
    frames = []
    for j in range(f):
        seconds = (int(ticks[j]) - r.freeze_end_tick) / rate
        teams: dict[str, list[dict[str, Any]]] = {"T": [], "CT": []}
        for i, player in enumerate(r.players):
            if not present[i, j]:
                continue
            k = i * f + j
            alive = bool(r.alive[i, j])
            has_bomb = bool(r.has_bomb[i, j])
            inventory = [*player.inventory, *(["C4"] if has_bomb else [])] if alive else []
            value = player.equipment_value if alive else 0
            teams[player.side].append(
                {
                    "steamID": player.steam_id,
                    "name": player.name,
                    "team": match.team_names[player.side],
                    "side": player.side,
                    "x": columns["x"][k],
                    "y": columns["y"][k],
                    "z": columns["z"][k],
                    "eyeX": columns["x"][k],
                    "eyeY": columns["y"][k],
                    "eyeZ": columns["eyeZ"][k],
                    "velocityX": columns["vx"][k],
                    "velocityY": columns["vy"][k],
                    "velocityZ": columns["vz"][k],
                    "viewX": columns["yaw"][k],
                    "viewY": 0.0,
                    "hp": int(r.hp[i, j]),
                    "armor": int(r.armor[i, j]),
                    "activeWeapon": str(r.weapon[i, j]),
                    "flashGrenades": 0,
                    "smokeGrenades": 0,
                    "heGrenades": 0,
                    "fireGrenades": 0,
                    "totalUtility": 0,
                    "lastPlaceName": str(place[i, j]),
                    "isAlive": alive,
                    "isBlinded": False,
                    "isAirborne": False,
                    "isDucking": False,
                    "isDefusing": bool(flags["defusing"][i, j]),
                    "isPlanting": bool(flags["planting"][i, j]),
                    "isReloading": False,
                    "isInBombZone": bool(flags["in_bomb_zone"][i, j]),
                    "isInBuyZone": bool(flags["in_buy_zone"][i, j]),
                    "isStanding": alive,
                    "isScoped": False,
                    "isWalking": False,
                    "inventory": [
                        {
                            "weaponName": name,
                            "weaponClass": _weapon_class(name),
                            "ammoInMagazine": None,
                            "ammoInReserve": None,
                        }
                        for name in inventory
                    ],
                    "spotters": [],
                    "equipmentValue": value,
                    "equipmentValueFreezetimeEnd": player.equipment_value,
                    "equipmentValueRoundStart": player.start_equipment_value,
                    "cash": None,
                    "cashSpendThisRound": player.cash_spent,
                    "cashSpendTotal": spent_total[_key(player)],
                    "hasHelmet": bool(r.helmet[i, j]),
                    "hasDefuse": bool(r.has_defuser[i, j]),
                    "hasBomb": has_bomb,
                    "ping": 0,
                    "zoomLevel": 0,
                }
            )
        x, y, z = bomb[3 * j : 3 * j + 3]
        frames.append(
            {
                "frameID": j,
                "globalFrameID": global_frame + j,
                "isKillFrame": False,
                "tick": int(ticks[j]),
                "seconds": seconds,
                "clockTime": _clock(seconds, plant_s),
                "t": _team_state(match, "T", teams["T"]),
                "ct": _team_state(match, "CT", teams["CT"]),
                "bombPlanted": bool(r.bomb_planted[j]),
                "bombsite": str(r.bombsite[j]),
                "bomb": None if x is None else {"x": x, "y": y, "z": z},
                "projectiles": [],
                "smokes": [],
                "fires": [],
            }
        )
    return frames


def _team_state(match: MatchRecord, side: str, players: list[dict[str, Any]]) -> dict[str, Any]:
    return {
        "side": side,
        "teamName": match.team_names[side],
        "teamEqVal": sum(p["equipmentValue"] for p in players),
        "alivePlayers": sum(1 for p in players if p["isAlive"]),
        "totalUtility": 0,
        "players": players,
    }
