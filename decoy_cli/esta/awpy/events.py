"""A CS2 round's events from awpy's tables as ESTA's: kills, damages and bomb events with
ESTA's names (decoy_cli/esta/awpy/names.py) and columns, and the defuse's start where the ticks
show it. An unknown weapon or hit group is kept unnamed and a named warning of the round.
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from decoy_cli.csgo import HAMMER_TO_M
from decoy_cli.esta.awpy.names import (
    CARRIER_EVENTS,
    bomb_action,
    bomb_site,
    hit_group,
    side_name,
    weapon_name,
)
from decoy_cli.esta.frames import MAX_COORD_U, RoundClock
from decoy_cli.esta.reader import UTILITY_COLUMNS, empty_utility
from decoy_cli.esta.schema import BombEvent, DamageEvent, FlashEvent, Invalid, KillEvent

MAX_HP = 100
"""A player's health at most (the game's)."""
MAX_RAW_DAMAGE = 1000
"""Most HP one hit may deal before the victim's health caps it: about twice the game's most (an
AWP head shot, 115 x 4; the real events' largest is 452)."""
MAX_BLIND_S = 20.0
"""Longest blind kept, seconds: a flashbang blinds for a few (awpy 3's own tests bound its
durations by 6 s); longer is not a flash."""


def round_events(
    kills: pd.DataFrame,
    damages: pd.DataFrame,
    bomb: pd.DataFrame,
    ticks: pd.DataFrame,
    plant_site: str,
    warnings: list[str],
    *,
    blinds: pd.DataFrame | None = None,
) -> dict[str, list]:
    """A round's kills, damages and bomb events (its rows of awpy's tables, in tick order) as
    ESTA event structs; `ticks` are the round's tick rows (a defuse's start, `_defuse_starts`)
    and `plant_site` the rounds table's site of its plant."""
    bomb_rows = [_bomb_event(row, plant_site, warnings) for row in _records(bomb)]
    return {
        "kills": [KillEvent(**_kill(row, warnings)) for row in _records(kills)],
        "damages": [DamageEvent(**_damage(row, warnings)) for row in _records(damages)],
        "bomb": _defuse_starts([BombEvent(**row) for row in bomb_rows if row is not None], ticks),
        "flashes": [] if blinds is None else _flashes(blinds, warnings),
    }


def _flashes(blinds: pd.DataFrame, warnings: list[str]) -> list:
    """awpy 3's blinds as ESTA's flashes (attacker: the thrower; player: the one blinded); a
    blind whose duration is not a positive number of seconds is left out, named."""
    out = []
    for row in _records(blinds):
        duration = row.get("duration")
        if not (isinstance(duration, int | float) and 0 < duration <= MAX_BLIND_S):
            shown = f"{duration:.3g}" if isinstance(duration, int | float) else repr(duration)
            warnings.append(f"a blind at tick {row['tick']} lasts {shown:.20} s: left out")
            continue
        flashed = _player(row, "victim", "player")
        flashed.pop("playerViewX")
        flashed.pop("playerViewY")
        out.append(
            FlashEvent(
                tick=row["tick"],
                **_player(row, "attacker", "attacker"),
                **flashed,
                flashDuration=float(duration),
            )
        )
    return out


def utility_table(
    table: pd.DataFrame | None, kind: str, clock: RoundClock, warnings: list[str]
) -> pd.DataFrame:
    """A round's smokes or fires (awpy's rows) as `UTILITY_COLUMNS`; one without an end, or
    ending before it starts, keeps a NaN end and is named."""
    if table is None or not len(table):
        return empty_utility()
    start = table["start_tick"].to_numpy(dtype=np.float64)
    end = pd.to_numeric(table["end_tick"], errors="coerce").to_numpy(dtype=np.float64)
    for tick in start[~(end >= start)]:
        warnings.append(
            f"a {kind} bursting at tick {int(tick)} has no end in the data: not used in the fight"
        )
    end = np.where(end >= start, end, np.nan)
    where = table[["x", "y", "z"]].to_numpy(np.float64)
    with np.errstate(invalid="ignore"):
        off = ~(np.abs(where) <= MAX_COORD_U).all(axis=1)
    if off.any():
        x, y, z = where[int(np.argmax(off))]
        raise Invalid(f"a {kind} bursts at ({x:.3g}, {y:.3g}, {z:.3g}) u, off the map")

    def column(name: str) -> np.ndarray:
        values = table[name] if name in table else pd.Series(None, index=table.index)
        return values.to_numpy(dtype=object, na_value=None)

    out = pd.DataFrame(
        {
            "start_tick": start,
            "end_tick": end,
            "start_s": clock.seconds(start),
            "end_s": clock.seconds(end),
            **{f"{a}_m": table[a].to_numpy(np.float64) * HAMMER_TO_M for a in "xyz"},
            "thrower_name": column("thrower_name"),
            "thrower_side": [None if s is None else side_name(s) for s in column("thrower_side")],
            "thrower_steamid": pd.array(
                [steam_id(s) for s in column("thrower_steamid")], dtype="Int64"
            ),
        }
    )
    return out[list(UTILITY_COLUMNS)].reset_index(drop=True)


def _defuse_starts(bomb: list, rows: pd.DataFrame) -> list:
    """The bomb events with a `defuse_start` before each `defuse` that has none, where the
    defuser's ticks show him defusing (awpy 3's `is_defusing`, awpy 2's with the prop): the
    first tick of the run of defusing ticks that ends in the defuse. awpy writes no event for
    the start of a defuse."""
    if "is_defusing" not in rows or not len(bomb):
        return bomb
    out = list(bomb)
    for event in bomb:
        if event.bombAction != "defuse" or any(
            e.bombAction == "defuse_start" and e.tick <= event.tick for e in bomb
        ):
            continue
        key = str(event.playerSteamID) if event.playerSteamID else event.playerName
        keys, _ = row_keys(rows)
        mine = rows[(keys == key) & (rows["tick"].to_numpy(np.int64) <= event.tick)]
        mine = mine.sort_values("tick", kind="stable")
        defusing = mine["is_defusing"].to_numpy(dtype=object, na_value=False).astype(bool)
        if not defusing.size or not defusing[-1]:
            continue
        stops = np.flatnonzero(~defusing)
        first = stops[-1] + 1 if stops.size else 0
        start = int(mine["tick"].iloc[first])
        out.append(
            BombEvent(**{**_struct_fields(event), "tick": start, "bombAction": "defuse_start"})
        )
    return sorted(out, key=lambda e: e.tick)


def _struct_fields(event: object) -> dict[str, object]:
    return {name: getattr(event, name) for name in event.__struct_fields__}  # type: ignore[attr-defined]


def _records(table: pd.DataFrame) -> list[dict[str, object]]:
    """Rows as dicts with None for every null."""
    return [
        {k: (None if is_null(v) else v) for k, v in row.items()} for row in table.to_dict("records")
    ]


def is_null(value: object) -> bool:
    return value is None or value is pd.NA or (isinstance(value, float) and np.isnan(value))


def _player(row: dict[str, object], who: str, esta: str) -> dict[str, object]:
    """One player's columns of an event as ESTA names them (`esta` is the ESTA prefix)."""
    side = row.get(f"{who}_side")
    return {
        f"{esta}SteamID": steam_id(row.get(f"{who}_steamid")),
        f"{esta}Name": row.get(f"{who}_name"),
        f"{esta}Side": None if side is None else side_name(side),
        f"{esta}X": row.get(f"{who}_x"),
        f"{esta}Y": row.get(f"{who}_y"),
        f"{esta}Z": row.get(f"{who}_z"),
        f"{esta}ViewX": _yaw(row.get(f"{who}_yaw")),
        f"{esta}ViewY": row.get(f"{who}_pitch"),
    }


def steam_id(value: object) -> int | None:
    """A steamid as an int; null or 0 (a bot) is None."""
    if is_null(value) or value == 0:
        return None
    return int(value)  # type: ignore[call-overload]


def _yaw(value: object) -> float | None:
    return None if value is None else float(value) % 360.0  # type: ignore[arg-type]


def _event_weapon(row: dict[str, object], warnings: list[str]) -> str | None:
    """ESTA's name of an event's weapon; an unknown one is None and a named warning."""
    raw = row.get("weapon")
    name = weapon_name(raw, "item")
    if name is None:
        warnings.append(f"unknown weapon {raw!r} at tick {row['tick']}: kept unnamed")
    return name or None


def _event_hit_group(row: dict[str, object], warnings: list[str]) -> str | None:
    raw = row.get("hitgroup")
    group = hit_group(raw)
    if group is None:
        warnings.append(f"unknown hit group {raw!r} at tick {row['tick']}: kept unnamed")
    return group or None


def _kill(row: dict[str, object], warnings: list[str]) -> dict[str, object]:
    attacker = _player(row, "attacker", "attacker")
    victim = _player(row, "victim", "victim")
    assister = _player(row, "assister", "assister")
    penetrated = row.get("penetrated")
    return {
        "tick": row["tick"],
        **attacker,
        **victim,
        "assisterSteamID": assister["assisterSteamID"],
        "assisterName": assister["assisterName"],
        "assisterSide": assister["assisterSide"],
        "weapon": _event_weapon(row, warnings),
        "isHeadshot": row.get("headshot"),
        "isSuicide": attacker["attackerName"] == victim["victimName"],
        "isTeamkill": attacker["attackerSide"] == victim["victimSide"],
        "thruSmoke": row.get("thrusmoke"),
        "noScope": row.get("noscope"),
        "isWallbang": None if penetrated is None else bool(penetrated),
        "penetratedObjects": penetrated,
        "attackerBlinded": row.get("attackerblind"),
        "distance": row.get("distance"),
    }


def _damage(row: dict[str, object], warnings: list[str]) -> dict[str, object]:
    taken, raw = row.get("dmg_health_taken"), row.get("dmg_health")
    if taken is not None and not 0 <= float(taken) <= MAX_HP:  # type: ignore[arg-type]
        raise Invalid(f"the damage at tick {row['tick']} takes {taken} HP (a player has {MAX_HP})")
    if raw is not None and not 0 <= float(raw) <= MAX_RAW_DAMAGE:  # type: ignore[arg-type]
        raise Invalid(f"the damage at tick {row['tick']} deals {raw} HP raw (no hit deals that)")
    attacker = _player(row, "attacker", "attacker")
    victim = _player(row, "victim", "victim")
    return {
        "tick": row["tick"],
        **attacker,
        **victim,
        "weapon": _event_weapon(row, warnings) or "World",
        "hpDamage": row.get("dmg_health"),
        "hpDamageTaken": row.get("dmg_health_taken"),
        "armorDamage": row.get("dmg_armor"),
        "armorDamageTaken": row.get("dmg_armor_taken"),
        "hitGroup": _event_hit_group(row, warnings),
        "isFriendlyFire": attacker["attackerSide"] is not None
        and attacker["attackerSide"] == victim["victimSide"],
        "distance": _distance(row),
    }


def _distance(row: dict[str, object]) -> float | None:
    """awpy's distance where given, else the attacker-victim distance in Hammer units."""
    if row.get("distance") is not None:
        return float(row["distance"])  # type: ignore[arg-type]
    ends = [row.get(f"{who}_{axis}") for who in ("attacker", "victim") for axis in "xyz"]
    if any(value is None for value in ends):
        return None
    a, b = np.array(ends[:3], dtype=np.float64), np.array(ends[3:], dtype=np.float64)
    return float(np.linalg.norm(a - b))


def _bomb_event(
    row: dict[str, object], plant_site: str, warnings: list[str]
) -> dict[str, object] | None:
    """A bomb event as ESTA writes it (the plant's site is the round's where the row names a
    place, as awpy 2 does); None for the events ESTA has no name for (drop, pick-up)."""
    action = bomb_action(row.get("event"))
    if action is None:
        if row.get("event") not in CARRIER_EVENTS:
            warnings.append(f"unknown bomb event {row.get('event')!r:.40} at tick {row['tick']}")
        return None
    site = bomb_site(row.get("site")) or (plant_site if action == "plant" else "")
    return {
        "tick": row["tick"],
        "playerSteamID": steam_id(row.get("steamid")),
        "playerName": row.get("name"),
        "playerX": row.get("x"),
        "playerY": row.get("y"),
        "playerZ": row.get("z"),
        "bombAction": action,
        "bombSite": site or None,
    }


def row_keys(rows: pd.DataFrame) -> tuple[np.ndarray, np.ndarray]:
    """Each tick row's player key (the steamid as text, else the name) and steamid (None where
    null or 0, a bot)."""
    names = texts(rows["name"], "")
    raw = (
        rows["steamid"].to_numpy(dtype=object, na_value=None)
        if "steamid" in rows
        else np.full(len(rows), None, dtype=object)
    )
    steam = np.array([steam_id(s) for s in raw], dtype=object)
    keys = np.array([n if s is None else str(s) for n, s in zip(names, steam, strict=True)], object)
    return keys, steam


def texts(values: pd.Series, missing: object) -> np.ndarray:
    """A text column as an object array, each distinct text one object however many rows hold
    it (`missing` where null): a long name costs its length once, not once a row."""
    codes, uniques = pd.factorize(values, use_na_sentinel=True)
    table = np.empty(len(uniques) + 1, dtype=object)
    table[:-1] = list(uniques)
    table[-1] = missing  # code -1, a null
    return table[codes]
