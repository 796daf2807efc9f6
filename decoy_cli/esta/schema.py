"""The part of the awpy 1.x match schema the reader decodes, as msgspec structs.

Decoding straight into these structs (instead of generic dicts) skips every key the project does
not use, checks every type on the way with a JSON path in the message, and is faster than orjson
into dicts (benchmarks/studies/json_decoders.py compares the decoders). Every field is optional
and may be null; numbers are declared `float` so that ints written as floats (and floats written
as ints) pass, and the builders check integrality where an int is meant. Unknown keys are ignored.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Literal, TypeAlias

import msgspec

Kind = Literal["int", "float", "bool", "str", "steamid"]
"""How an event column is typed: nullable int, float (null -> NaN), nullable bool, str, steamID."""

_DECODED_TYPE: dict[Kind, object] = {
    "int": float | None,
    "float": float | None,
    "bool": bool | None,
    "str": str | None,
    "steamid": int | float | None,
}


class Invalid(Exception):
    """A problem inside one round; the reader turns it into an EstaError naming file and round."""


class PlayerState(msgspec.Struct):
    """One player in one frame (the keys the reader uses)."""

    steamID: int | float | None = None
    name: str | None = None
    x: float | None = None
    y: float | None = None
    z: float | None = None
    velocityZ: float | None = None
    viewX: float | None = None
    hp: float | None = None
    armor: float | None = None
    hasHelmet: bool | None = None
    hasDefuse: bool | None = None
    hasBomb: bool | None = None
    isAlive: bool | None = None
    activeWeapon: str | None = None


class TeamState(msgspec.Struct):
    """One side in one frame."""

    players: list[PlayerState] | None = None


class Point(msgspec.Struct):
    """An x, y, z position in Hammer units."""

    x: float | None = None
    y: float | None = None
    z: float | None = None


class FrameState(msgspec.Struct):
    """One frame (2 per second in ESTA)."""

    tick: float | None = None
    seconds: float | None = None
    t: TeamState | None = None
    ct: TeamState | None = None
    bombPlanted: bool | None = None
    bombsite: str | None = None
    bomb: Point | None = None


DAMAGE_COLUMNS: dict[str, Kind] = {
    "tick": "int",
    "seconds": "float",
    "clockTime": "str",
    "attackerSteamID": "steamid",
    "attackerName": "str",
    "attackerTeam": "str",
    "attackerSide": "str",
    "attackerX": "float",
    "attackerY": "float",
    "attackerZ": "float",
    "attackerViewX": "float",
    "attackerViewY": "float",
    "attackerStrafe": "bool",
    "victimSteamID": "steamid",
    "victimName": "str",
    "victimTeam": "str",
    "victimSide": "str",
    "victimX": "float",
    "victimY": "float",
    "victimZ": "float",
    "victimViewX": "float",
    "victimViewY": "float",
    "weapon": "str",
    "weaponClass": "str",
    "hpDamage": "int",
    "hpDamageTaken": "int",
    "armorDamage": "int",
    "armorDamageTaken": "int",
    "hitGroup": "str",
    "isFriendlyFire": "bool",
    "distance": "float",
    "zoomLevel": "int",
}
"""Damage event columns, in the awpy 1.x order."""

KILL_COLUMNS: dict[str, Kind] = {
    "tick": "int",
    "seconds": "float",
    "clockTime": "str",
    "attackerSteamID": "steamid",
    "attackerName": "str",
    "attackerTeam": "str",
    "attackerSide": "str",
    "attackerX": "float",
    "attackerY": "float",
    "attackerZ": "float",
    "attackerViewX": "float",
    "attackerViewY": "float",
    "victimSteamID": "steamid",
    "victimName": "str",
    "victimTeam": "str",
    "victimSide": "str",
    "victimX": "float",
    "victimY": "float",
    "victimZ": "float",
    "victimViewX": "float",
    "victimViewY": "float",
    "assisterSteamID": "steamid",
    "assisterName": "str",
    "assisterTeam": "str",
    "assisterSide": "str",
    "isSuicide": "bool",
    "isTeamkill": "bool",
    "isWallbang": "bool",
    "penetratedObjects": "int",
    "isFirstKill": "bool",
    "isHeadshot": "bool",
    "victimBlinded": "bool",
    "attackerBlinded": "bool",
    "flashThrowerSteamID": "steamid",
    "flashThrowerName": "str",
    "flashThrowerTeam": "str",
    "flashThrowerSide": "str",
    "noScope": "bool",
    "thruSmoke": "bool",
    "distance": "float",
    "isTrade": "bool",
    "playerTradedName": "str",
    "playerTradedTeam": "str",
    "playerTradedSteamID": "steamid",
    "weapon": "str",
    "weaponClass": "str",
}
"""Kill event columns, in the awpy 1.x order."""

BOMB_EVENT_COLUMNS: dict[str, Kind] = {
    "tick": "int",
    "seconds": "float",
    "clockTime": "str",
    "playerSteamID": "steamid",
    "playerName": "str",
    "playerTeam": "str",
    "playerX": "float",
    "playerY": "float",
    "playerZ": "float",
    "bombAction": "str",
    "bombSite": "str",
}
"""Bomb event columns, in the awpy 1.x order."""

FLASH_COLUMNS: dict[str, Kind] = {
    "tick": "int",
    "seconds": "float",
    "clockTime": "str",
    "attackerSteamID": "steamid",
    "attackerName": "str",
    "attackerTeam": "str",
    "attackerSide": "str",
    "attackerX": "float",
    "attackerY": "float",
    "attackerZ": "float",
    "attackerViewX": "float",
    "attackerViewY": "float",
    "playerSteamID": "steamid",
    "playerName": "str",
    "playerTeam": "str",
    "playerSide": "str",
    "playerX": "float",
    "playerY": "float",
    "playerZ": "float",
    "playerViewX": "float",
    "playerViewY": "float",
    "flashDuration": "float",
}
"""Flash events (attacker = thrower, player = the flashed player), in the awpy 1.x order."""


def _event_struct(name: str, columns: dict[str, Kind]) -> type[msgspec.Struct]:
    """A struct with one optional field per column, typed as the column kind decodes."""
    return msgspec.defstruct(
        name, [(column, _DECODED_TYPE[kind], None) for column, kind in columns.items()]
    )


if TYPE_CHECKING:
    # The event structs are built from the column tables at run time (msgspec.defstruct), which a
    # type checker cannot follow: it sees them as plain structs. msgspec resolves the (postponed)
    # annotations of RoundState with the run-time classes below, so decoding is unchanged.
    DamageEvent: TypeAlias = msgspec.Struct
    KillEvent: TypeAlias = msgspec.Struct
    BombEvent: TypeAlias = msgspec.Struct
    FlashEvent: TypeAlias = msgspec.Struct
else:
    DamageEvent = _event_struct("DamageEvent", DAMAGE_COLUMNS)
    KillEvent = _event_struct("KillEvent", KILL_COLUMNS)
    BombEvent = _event_struct("BombEvent", BOMB_EVENT_COLUMNS)
    FlashEvent = _event_struct("FlashEvent", FLASH_COLUMNS)


class RoundHead(msgspec.Struct):
    """Just the round number: decoded on its own when the full round fails to decode."""

    roundNum: float | None = None


class RoundState(msgspec.Struct):
    """One round (`gameRounds[i]`): the keys the reader uses."""

    roundNum: float | None = None
    startTick: float | None = None
    freezeTimeEndTick: float | None = None
    endTick: float | None = None
    bombPlantTick: float | None = None
    winningSide: str | None = None
    roundEndReason: str | None = None
    tBuyType: str | None = None
    ctBuyType: str | None = None
    frames: list[FrameState] | None = None
    damages: list[DamageEvent] | None = None
    kills: list[KillEvent] | None = None
    bombEvents: list[BombEvent] | None = None
    flashes: list[FlashEvent] | None = None
