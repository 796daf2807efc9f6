"""The frames of a written round: every player's state per frame as awpy 1.x writes it.

Hammer units stored as float32 and printed in their shortest form, `seconds` and `clockTime`
from the tick, velocities from consecutive frames, eye positions 64 u above the feet, team
equipment values, alive counts and buy types (decoy_cli/esta/writer.py writes the rest).
"""

from __future__ import annotations

import numpy as np

from decoy_cli.csgo import HAMMER_TO_M
from decoy_cli.esta.records import (
    BOMB_TIMER_S,
    ROUND_TIME_S,
    EstaRoundRecord,
    MatchRecord,
    player_key,
)
from decoy_cli.files import JsonObject, JsonValue
from decoy_cli.geometry import eye_point
from decoy_cli.weapons import WEAPONS

_BUY_TYPES = ((5_000, "Full Eco"), (10_000, "Semi Eco"), (20_000, "Semi Buy"))


def to_hammer(values: np.ndarray) -> np.ndarray:
    """Metres to Hammer units, as float32 (what awpy stores); NaN stays NaN."""
    return (np.asarray(values, dtype=np.float64) / HAMMER_TO_M).astype(np.float32)


def floats(values: np.ndarray) -> list[float | None]:
    """float32 values as Python floats printed in their shortest float32 form; NaN -> None."""
    flat = np.asarray(values, dtype=np.float32).ravel()
    text = flat.astype(str)
    return [None if s == "nan" else float(s) for s in text]


def buy_type(value: int) -> str:
    for limit, name in _BUY_TYPES:
        if value < limit:
            return name
    return "Full Buy"


def clock_time(seconds: float, planted_seconds: float | None) -> str:
    """awpy's `clockTime`: the round clock counting down, the bomb timer after a plant."""
    if planted_seconds is not None and seconds >= planted_seconds:
        left = BOMB_TIMER_S - (seconds - planted_seconds)
    else:
        left = ROUND_TIME_S - seconds
    whole = max(0, int(np.ceil(round(left, 6))))
    return f"{whole // 60:02d}:{whole % 60:02d}"


def weapon_class(name: str) -> str | None:
    return WEAPONS[name][0] if name in WEAPONS else None


def frame_documents(
    match: MatchRecord,
    r: EstaRoundRecord,
    plant_s: float | None,
    spent_total: dict[str, int],
    global_frame: int,
) -> list[JsonValue]:
    """Every frame of a round, both sides, with the full awpy player state."""
    rate = match.tick_rate
    ticks = np.asarray(r.frame_ticks, dtype=np.int64)
    p, f = len(r.players), len(ticks)
    position = np.asarray(r.position, dtype=np.float64)
    present = np.all(np.isfinite(position), axis=2)
    hammer = to_hammer(position)
    # horizontal velocity from the previous frame (u/s); 0 in the first frame and next to an
    # absence
    velocity = np.zeros((p, f, 2), dtype=np.float32)
    if f > 1:
        dt = np.diff(ticks) / rate
        moved = np.diff(hammer[..., :2].astype(np.float64), axis=1)
        step = moved / np.where(dt > 0, dt, np.inf)[:, None]
        moving = present[:, 1:] & present[:, :-1] & np.asarray(r.alive)[:, 1:]
        velocity[:, 1:] = np.where(moving[..., None], step, 0.0).astype(np.float32)
    eye_z = to_hammer(eye_point(position)[..., 2])
    columns = {
        "x": floats(hammer[..., 0]),
        "y": floats(hammer[..., 1]),
        "z": floats(hammer[..., 2]),
        "eyeZ": floats(eye_z),
        "vx": floats(velocity[..., 0]),
        "vy": floats(velocity[..., 1]),
        "yaw": floats(np.asarray(r.yaw)),
    }
    flags = {
        name: np.zeros((p, f), bool) if getattr(r, name) is None else np.asarray(getattr(r, name))
        for name in ("planting", "defusing", "in_bomb_zone", "in_buy_zone")
    }
    place = np.full((p, f), "", dtype=object) if r.place is None else np.asarray(r.place)
    bomb = floats(to_hammer(np.asarray(r.bomb_position)))
    frames: list[JsonValue] = []
    for j in range(f):
        seconds = (int(ticks[j]) - r.freeze_end_tick) / rate
        teams: dict[str, list[JsonValue]] = {"T": [], "CT": []}
        team_value = {"T": 0, "CT": 0}
        team_alive = {"T": 0, "CT": 0}
        for i, player in enumerate(r.players):
            if not present[i, j]:
                continue
            k = i * f + j
            alive = bool(r.alive[i, j])
            has_bomb = bool(r.has_bomb[i, j])
            inventory = [*player.inventory, *(["C4"] if has_bomb else [])] if alive else []
            value = player.equipment_value if alive else 0
            team_value[player.side] += value
            team_alive[player.side] += alive
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
                    # awpy's velocityZ is 0 on the ground, not the change of height between
                    # frames, and a record does not say when a player was in the air: unknown
                    "velocityZ": None,
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
                            "weaponClass": weapon_class(name),
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
                    "cashSpendTotal": spent_total[player_key(player)],
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
                "clockTime": clock_time(seconds, plant_s),
                "t": _team_state(match, "T", teams["T"], team_value["T"], team_alive["T"]),
                "ct": _team_state(match, "CT", teams["CT"], team_value["CT"], team_alive["CT"]),
                "bombPlanted": bool(r.bomb_planted[j]),
                "bombsite": str(r.bombsite[j]),
                "bomb": None if x is None else {"x": x, "y": y, "z": z},
                "projectiles": [],
                "smokes": [],
                "fires": [],
            }
        )
    return frames


def _team_state(
    match: MatchRecord, side: str, players: list[JsonValue], value: int, alive: int
) -> JsonObject:
    """A side's state in a frame: its `players`, their equipment `value` and `alive` count."""
    return {
        "side": side,
        "teamName": match.team_names[side],
        "teamEqVal": value,
        "alivePlayers": alive,
        "totalUtility": 0,
        "players": players,
    }
