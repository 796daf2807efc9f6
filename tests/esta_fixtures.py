"""Tiny ESTA match files in the real awpy 1.x shape, generated for tests (not real data).

`make_match()` returns the JSON document of a 3-round de_dust2 match with the quirks real files
have: 5 T and 4 CT players whose order changes in every frame, one CT player missing from one
frame, a T player without steamID (keyed by name) and a bot (steamID 0), ints written as floats,
nulls, unknown keys at every level, a bomb plant with bomb events, damages and kills, and a round
without frames (as in the events-only real file). `write_match()` writes it as `.json.xz` or
`.json`. The helpers `expected_hammer_position` and the constants below let tests check values.

Usage from another test module: `from esta_fixtures import make_match, write_match`.
"""

from __future__ import annotations

import copy
import json
import lzma
from pathlib import Path
from typing import Any

MATCH_ID = "fixture-0001"
TICK_RATE = 128
FRAME_STEP = 64
"""Ticks between frames (2 frames per second at 128 tick)."""

T_PLAYERS = [
    # (name, steamID); t4 has no steamID (keyed by name), t5 is a bot (steamID 0)
    ("t1", 76561198000000001),
    ("t2", 76561198000000002),
    ("t3", 76561198000000003),
    ("t4", None),
    ("BOT t5", 0),
]
CT_PLAYERS = [
    ("ct1", 76561198000000011),
    ("ct2", 76561198000000012),
    ("ct3", 76561198000000013),
    ("ct4", 76561198000000014),
]
T_KEYS = ["76561198000000001", "76561198000000002", "76561198000000003", "BOT t5", "t4"]
"""Row order of the T players in a Round: sorted by key (steamID string, else name)."""
CT_KEYS = [str(steam_id) for _, steam_id in CT_PLAYERS]

ROUND1_TICKS = [1000 + FRAME_STEP * j for j in range(4)]
ROUND1_FREEZE_END = 990
ROUND2_TICKS = [5000 + FRAME_STEP * j for j in range(6)]
ROUND2_FREEZE_END = 5000
ROUND2_PLANT_FRAME = 3
ROUND2_PLANT_TICK = ROUND2_TICKS[ROUND2_PLANT_FRAME] - 10
MISSING_CT = ("ct4", 1, 2)
"""(name, round, frame): the CT player absent from that frame."""
DEAD_T = ("t3", 1, 3)
"""(name, round, frame): the T player dead (hp 0) from that frame on."""
BOMB_HAMMER = (1200.0, 2500.0, 100.0)
"""Bomb position in round 2 from the plant on (Hammer units)."""

_UNKNOWN = {"someNewKey": {"nested": [1, 2.5, None]}}


def expected_hammer_position(name: str, frame: int) -> tuple[float, float, float]:
    """Where player `name` stands in a frame of rounds 1 and 2 (Hammer units)."""
    names = [n for n, _ in T_PLAYERS + CT_PLAYERS]
    i = names.index(name)
    return (-1000.0 + 150.0 * i + 12.5 * frame, 800.0 - 40.0 * i - 7.25 * frame, 10.0 * (i % 3))


def _player(
    name: str, steam_id: int | None, side: str, frame: int, weapon: str | None, hp: float
) -> dict[str, Any]:
    """One player state with the full awpy 1.x key set."""
    x, y, z = expected_hammer_position(name, frame)
    return {
        "steamID": steam_id,
        "name": name,
        "team": "Team A" if side == "T" else "Team B",
        "side": side,
        "x": x,
        "y": y,
        "z": z,
        "eyeX": x,
        "eyeY": y,
        "eyeZ": z + 64.0,
        "velocityX": 12.5,
        "velocityY": -7.25,
        "velocityZ": 0,
        "viewX": 45.0 * frame + (10.0 if side == "T" else 190.0),
        "viewY": 1.5,
        "hp": hp,
        "armor": 100,
        "activeWeapon": weapon,
        "flashGrenades": 0,
        "smokeGrenades": 1,
        "heGrenades": 0,
        "fireGrenades": 0,
        "totalUtility": 300,
        "lastPlaceName": "LongDoors",
        "isAlive": hp > 0,
        "isBlinded": False,
        "isAirborne": False,
        "isDucking": False,
        "isDefusing": False,
        "isPlanting": False,
        "isReloading": False,
        "isInBombZone": False,
        "isInBuyZone": frame == 0,
        "isStanding": True,
        "isScoped": False,
        "isWalking": False,
        "inventory": [{"weaponName": weapon, "weaponClass": "Rifle", "ammoInMagazine": 30}],
        "spotters": [],
        "equipmentValue": 3700,
        "cash": 800,
        "hasHelmet": side == "CT",
        "hasDefuse": name == "ct1",
        "hasBomb": name == "t1",
        "ping": 5,
        "zoomLevel": 0,
        **_UNKNOWN,
    }


def _team(side: str, players: list[dict[str, Any]]) -> dict[str, Any]:
    return {
        "side": side,
        "teamName": "Team A" if side == "T" else "Team B",
        "teamEqVal": 20000,
        "alivePlayers": sum(1 for p in players if p["hp"] > 0),
        "totalUtility": 1500,
        "players": players,
    }


def _frame(round_num: int, j: int, tick: int, seconds: float | None) -> dict[str, Any]:
    """Frame j of round 1 or 2: players rotated by j so their order is never the same."""
    t_players = []
    for name, steam_id in T_PLAYERS:
        dead = (name, round_num) == DEAD_T[:2] and j >= DEAD_T[2]
        weapon = "" if name == "t2" else "AK-47"
        # ints written as floats in round 1, as in some real exports
        hp = 0 if dead else (100.0 if round_num == 1 else 100)
        player = _player(name, steam_id, "T", j, "" if dead else weapon, hp)
        if round_num == 1 and name == "t1" and j == 1:
            player["viewX"] = None
        if name == "t2" and round_num == 2:
            player["isAlive"] = None  # alive falls back to hp > 0
        t_players.append(player)
    ct_players = []
    for name, steam_id in CT_PLAYERS:
        if (name, round_num, j) == MISSING_CT:
            continue
        player = _player(name, steam_id, "CT", j, None if name == "ct1" else "M4A4", 100)
        ct_players.append(player)
    rotate_t, rotate_ct = j % len(t_players), (2 * j) % len(ct_players)
    t_players = t_players[rotate_t:] + t_players[:rotate_t]
    ct_players = ct_players[rotate_ct:] + ct_players[:rotate_ct]
    planted = round_num == 2 and j >= ROUND2_PLANT_FRAME
    if planted:
        bomb: dict[str, Any] | None = dict(zip("xyz", BOMB_HAMMER, strict=True))
    elif round_num == 2 and j == 0:
        bomb = None
    else:
        bomb = dict(zip("xyz", expected_hammer_position("t1", j), strict=True))
    return {
        "frameID": j,
        "globalFrameID": 100 * round_num + j,
        "isKillFrame": False,
        "tick": tick,
        "seconds": seconds,
        "clockTime": "01:55",
        "t": _team("T", t_players),
        "ct": _team("CT", ct_players),
        "bombPlanted": planted,
        "bombsite": "A" if planted else "",
        "bomb": bomb,
        "projectiles": [],
        "smokes": [],
        "fires": [],
        **_UNKNOWN,
    }


def _damage(tick: float, attacker: str | None, victim: str, weapon: str, hp: int) -> dict[str, Any]:
    names = dict(T_PLAYERS + CT_PLAYERS)
    ax, ay, az = expected_hammer_position(attacker, 1) if attacker else (None, None, None)
    vx, vy, vz = expected_hammer_position(victim, 1)
    attacker_side = None if attacker is None else ("CT" if attacker.startswith("ct") else "T")
    return {
        "tick": tick,
        "seconds": 0.5,
        "clockTime": "01:54",
        "attackerSteamID": names[attacker] if attacker else None,
        "attackerName": attacker,
        "attackerTeam": None if attacker is None else "Team B",
        "attackerSide": attacker_side,
        "attackerX": ax,
        "attackerY": ay,
        "attackerZ": az,
        "attackerViewX": None if attacker is None else 90.0,
        "attackerViewY": None if attacker is None else 0.5,
        "attackerStrafe": None if attacker is None else False,
        "victimSteamID": names[victim],
        "victimName": victim,
        "victimTeam": "Team A",
        "victimSide": "T",
        "victimX": vx,
        "victimY": vy,
        "victimZ": vz,
        "victimViewX": 270.0,
        "victimViewY": 0.0,
        "weapon": weapon,
        "weaponClass": "Rifle" if attacker else "Equipment",
        "hpDamage": hp,
        "hpDamageTaken": min(hp, 100),
        "armorDamage": 4,
        "armorDamageTaken": 4,
        "hitGroup": "Head" if attacker else "Generic",
        "isFriendlyFire": False,
        "distance": 500.0 if attacker else None,
        "zoomLevel": 0,
        **_UNKNOWN,
    }


def _round_base(num: int, start: int, freeze_end: int, end: int) -> dict[str, Any]:
    return {
        "roundNum": num,
        "isWarmup": False,
        "startTick": start,
        "freezeTimeEndTick": freeze_end,
        "endTick": end,
        "endOfficialTick": end + 640,
        "bombPlantTick": None,
        "tScore": num - 1,
        "ctScore": 0,
        "endTScore": num,
        "endCTScore": 0,
        "ctTeam": "Team B",
        "tTeam": "Team A",
        "winningSide": "T",
        "winningTeam": "Team A",
        "losingTeam": "Team B",
        "roundEndReason": "TerroristsWin",
        "ctFreezeTimeEndEqVal": 20000,
        "ctRoundStartEqVal": 4000,
        "ctRoundSpendMoney": 16000,
        "ctBuyType": "Full Buy",
        "tFreezeTimeEndEqVal": 19000,
        "tRoundStartEqVal": 4000,
        "tRoundSpendMoney": 15000,
        "tBuyType": "Full Buy",
        "ctSide": {
            "teamName": "Team B",
            "players": [{"playerName": n, "steamID": s} for n, s in CT_PLAYERS],
        },
        "tSide": {
            "teamName": "Team A",
            "players": [{"playerName": n, "steamID": s} for n, s in T_PLAYERS],
        },
        "kills": [],
        "damages": [],
        "grenades": [],
        "bombEvents": [],
        "weaponFires": [],
        "flashes": [],
        "frames": [],
        **_UNKNOWN,
    }


def make_match() -> dict[str, Any]:
    """The 3-round fixture match as a JSON document (a fresh copy each call)."""
    round1 = _round_base(1, 900, ROUND1_FREEZE_END, 1300)
    round1["roundNum"] = 1.0  # an int written as a float
    round1["frames"] = [
        _frame(1, j, tick, (tick - ROUND1_FREEZE_END) / TICK_RATE)
        for j, tick in enumerate(ROUND1_TICKS)
    ]

    round2 = _round_base(2, 4900, ROUND2_FREEZE_END, 5400)
    round2["bombPlantTick"] = ROUND2_PLANT_TICK
    round2["roundEndReason"] = "TargetBombed"
    round2["frames"] = [
        _frame(2, j, tick, None if j == 1 else (tick - ROUND2_FREEZE_END) / TICK_RATE)
        for j, tick in enumerate(ROUND2_TICKS)
    ]
    round2["damages"] = [
        _damage(5070.0, "ct1", "t1", "M4A4", 27),  # nearest frame 1 (tick 5064)
        _damage(5100, "ct2", "t2", "M4A4", 120),  # 36 ticks after frame 1, 28 before frame 2
    ]
    kill = {
        key: value
        for key, value in _damage(5130, "ct2", "t2", "M4A4", 100).items()
        if not key.startswith(("hp", "armor", "hitGroup", "zoom", "attackerStrafe"))
    }
    round2["kills"] = [{**kill, "isHeadshot": True, "isFirstKill": True, "assisterSteamID": None}]
    round2["bombEvents"] = [
        _bomb_event(ROUND2_PLANT_TICK - 410, "plant_begin"),
        _bomb_event(ROUND2_PLANT_TICK, "plant"),
    ]

    round3 = _round_base(3, 8000, 9000, 12000)  # no frames: events only
    round3["winningSide"] = "CT"
    round3["roundEndReason"] = "CTWin"
    round3["damages"] = [_damage(9500, None, "t3", "World", 12)]

    return copy.deepcopy(
        {
            "matchID": MATCH_ID,
            "clientName": "fixture",
            "mapName": "de_dust2",
            "tickRate": TICK_RATE,
            "playbackTicks": 12000,
            "parserParameters": {"parseRate": 64, "parseFrames": True, "tradeTime": 5},
            "serverVars": {"roundTime": 115, "freezeTime": 15, "bombTimer": 40, "maxRounds": 30},
            "matchPhases": {"announcementMatchStarted": [900]},
            "playerConnections": [],
            "provenance": {"note": "generated by tests/esta_fixtures.py, not real data"},
            "gameRounds": [round1, round2, round3],
            **_UNKNOWN,
        }
    )


def shift_ticks(value: Any, by: int) -> Any:
    """A copy of `value` (a round, or any part of one) with every tick (keys `tick` and
    `...Tick`) later by `by`: a copy of a round that can follow it in a file, as the game's
    clock runs forwards across rounds."""
    if isinstance(value, dict):
        return {
            k: v + by
            if (k == "tick" or k.endswith("Tick")) and isinstance(v, int | float)
            else shift_ticks(v, by)
            for k, v in value.items()
        }
    if isinstance(value, list):
        return [shift_ticks(v, by) for v in value]
    return value


def _bomb_event(tick: int, action: str) -> dict[str, Any]:
    x, y, z = BOMB_HAMMER
    return {
        "tick": tick,
        "seconds": (tick - ROUND2_FREEZE_END) / TICK_RATE,
        "clockTime": "01:50",
        "playerSteamID": T_PLAYERS[0][1],
        "playerName": "t1",
        "playerTeam": "Team A",
        "playerX": x,
        "playerY": y,
        "playerZ": z,
        "bombAction": action,
        "bombSite": "A",
    }


def one_round_match(
    match_id: str, tick_rate: int, round_: dict[str, Any], client: str = "decoy tests"
) -> dict[str, Any]:
    """A match document of one de_dust2 round; event lists the round does not give are empty."""
    empty = ("kills", "damages", "grenades", "weaponFires", "flashes", "bombEvents")
    return {
        "matchID": match_id,
        "clientName": client,
        "mapName": "de_dust2",
        "tickRate": tick_rate,
        "gameRounds": [{key: [] for key in empty} | round_],
    }


def encode(document: Any) -> bytes:
    """JSON bytes as Python writes them (NaN and Infinity literals allowed)."""
    return json.dumps(document).encode()


def write_match(path: Path, document: Any = None, *, compress: bool | None = None) -> Path:
    """Write a document (default: `make_match()`); xz when the name ends in .xz or compress=True."""
    data = encode(make_match() if document is None else document)
    if compress or (compress is None and path.name.endswith(".xz")):
        data = lzma.compress(data)
    path.write_bytes(data)
    return path
