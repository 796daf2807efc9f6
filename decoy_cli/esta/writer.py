"""Write ESTA match files (awpy 1.x JSON, `.json.xz`) from round data in metres.

The inverse of the reader (decoy_cli/esta/reader.py) for the keys it reads, plus the rest of
the awpy 1.x key set that real files carry, so a written file looks like a real one to any
awpy-based tool: `MatchRecord` holds the rounds as arrays (P players by F frames, metres,
degrees, demo ticks) and event records; `match_document` turns it into the JSON document and
`write_match` writes it, xz-compressed for `.json.xz`, atomically.

Units are converted here, once: metres to Hammer units, stored as float32 values (what awpy
writes), printed in their shortest form so the file stays small. Values the data does not hold
(grenades, cash, ammunition) are zeros, empty lists or nulls, as awpy writes for them.
Derived per frame: `seconds` and `clockTime` from the tick, horizontal velocities from
consecutive frames (`velocityZ` is null: a record does not say when a player was in the air),
eye positions 64 u above the feet (standing), team equipment values and alive counts, buy types
from team equipment (awpy's "hltv" style thresholds, checked against the real files: Full Eco
below 5,000, Semi Eco below 10,000, Semi Buy below 20,000, else Full Buy) and the scores before
and after each round from the winners. Output is deterministic: the same record gives the same
bytes.
"""

from __future__ import annotations

import lzma
from collections.abc import Sequence
from pathlib import Path

import msgspec
import numpy as np

from decoy_cli.csgo import HAMMER_TO_M
from decoy_cli.errors import OutputError
from decoy_cli.esta.records import (
    BOMB_TIMER_S,
    FREEZE_TIME_S,
    ROUND_TIME_S,
    TRADE_TIME_S,
    BombEventRecord,
    DamageRecord,
    EstaRoundRecord,
    KillRecord,
    MatchRecord,
    PlayerRecord,
    check_round,
    player_key,
)
from decoy_cli.esta.written_frames import (
    buy_type,
    clock_time,
    floats,
    frame_documents,
    to_hammer,
    weapon_class,
)
from decoy_cli.files import JsonObject, JsonValue, write_atomic

XZ_PRESET = 6
"""xz preset: the default. Measured on an 8-round sample (14.3 MB of JSON): preset 6 gives 165 KB
in 2.0 s, 9 the same size, extreme 151 KB in 4.7-5.9 s."""

_ENCODER = msgspec.json.Encoder()


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


def match_document(match: MatchRecord) -> JsonObject:
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
    rounds: list[JsonValue] = []
    for record in match.rounds:
        check_round(record)
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


# ---- documents ---------------------------------------------------------------------------------


def _round_document(
    match: MatchRecord,
    r: EstaRoundRecord,
    scores: dict[str, int],
    spent_total: dict[str, int],
    global_frame: int,
) -> JsonObject:
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
        key = player_key(player)
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
        "ctBuyType": buy_type(freeze_value["CT"]),
        "tFreezeTimeEndEqVal": freeze_value["T"],
        "tRoundStartEqVal": start_value["T"],
        "tRoundSpendMoney": spent["T"],
        "tBuyType": buy_type(freeze_value["T"]),
        "ctSide": _side_roster(teams["CT"], side_players["CT"]),
        "tSide": _side_roster(teams["T"], side_players["T"]),
        "kills": [context.kill(k) for k in r.kills],
        "damages": [context.damage(d) for d in r.damages],
        "grenades": [],
        "bombEvents": [context.bomb_event(b) for b in r.bomb_events],
        "weaponFires": [],
        "flashes": [],
        "frames": frame_documents(match, r, plant_s, spent_total, global_frame),
    }


def _side_roster(team: str, players: list[PlayerRecord]) -> JsonObject:
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

    def _time(self, tick: int) -> JsonObject:
        seconds = (tick - self.r.freeze_end_tick) / self.rate
        return {"tick": tick, "seconds": seconds, "clockTime": clock_time(seconds, self.plant_s)}

    def _who(self, role: str, index: int) -> JsonObject:
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
    def _where(role: str, position: Sequence[float] | None, yaw: float | None) -> JsonObject:
        if position is None:
            x = y = z = view = None
        else:
            x, y, z = floats(to_hammer(np.asarray(position)))
            view = None if yaw is None else floats(np.array([yaw]))[0]
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
        return floats(np.array([metres / HAMMER_TO_M]))[0]

    def damage(self, d: DamageRecord) -> JsonObject:
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
            "weaponClass": weapon_class(d.weapon),
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

    def kill(self, k: KillRecord) -> JsonObject:
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
            "weaponClass": weapon_class(k.weapon),
        }

    def bomb_event(self, b: BombEventRecord) -> JsonObject:
        who = self._who("player", b.player)
        x, y, z = floats(to_hammer(np.asarray(b.position)))
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
