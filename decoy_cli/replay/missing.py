"""What the game needs and a round's data lacks, filled by stated rules; what the data contradicts.

A replay needs every player's weapon in hand (its damage and running speed), armour, helmet and
defuse kit, and the bomb's carrier, planter and defuser. ESTA files record them all; other
exports record none (the shared CS2 rounds: positions, HP, kills, the plant's tick and site).
`fill_missing` returns the round with each absent field filled and one line per filled field
naming the rule (`Filled.notes`); with `missing="error"` an absent field is an EstaError.

Rules, the first that applies:

* Weapon in hand (absent in every frame of a player): the firearm of the player's own kills in
  the round, each frame taking the weapon of its next kill (the last kill's after it); else the
  side's firearm kills in the round: mostly pistols, the side's pistol (`DEFAULT_PISTOL`: an eco
  or a pistol round), otherwise the side's most used rifle in them, the AWP aside (one player's
  weapon; `DEFAULT_RIFLE` if none); else the round's type: a pistol round (`is_pistol_round`) or
  awpy's buy type "Full Eco"/"Semi Eco", the side's pistol; otherwise the side's rifle.
* Armour, helmet and kit (armour absent in every frame: the export has no equipment): a player
  whose first weapon is a pistol has a vest in a pistol round (the $800 start buys a vest, not a
  helmet too) and nothing otherwise (an eco); any other weapon means a buy: vest, helmet, and a
  kit for a CT.
* Bomb carrier and planter (nobody holds the bomb in any frame, and the data has a plant): the T
  alive at the plant who stood in the plant's site (else in another site, else anywhere) and
  moved least over the plant's duration: he carries the bomb from the round's start and plants
  where he stood. A site the data names where no T stood gives way to the planter's (named).
  Without a plant nobody carries it (the replay plants only where the data did).
* Defuse (the round ended `BombDefused` with no `defuse` event): it began 5 s (kit) or 10 s
  before the round's end (the rules' durations), by the CT alive at the end nearest the bomb.
* Defuse start (a `defuse` event with no `defuse_start` before it: awpy writes none, and takes
  it from the ticks only where they record `is_defusing`): the defuser began 5 s (kit) or 10 s
  before the defuse.

`contradictions` names what the frames and the events say against each other (a victim alive
after its kill, a killer or victim never in the frames, a plant with no T alive, a defuse of a
bomb never planted, a winner the alive counts deny): named, and the round is replayed.
"""

from __future__ import annotations

from collections import Counter
from dataclasses import dataclass, replace
from typing import Literal

import numpy as np
import pandas as pd

from decoy_cli.csgo import is_pistol_round
from decoy_cli.errors import EstaError
from decoy_cli.esta import Round
from decoy_cli.esta.frames import Side
from decoy_cli.replay.bomb import bomb_events, data_plant_tick
from decoy_cli.sim.rules import RulesConfig
from decoy_cli.sim.sites import SiteZones
from decoy_cli.weapons import FIREARMS, WEAPONS

Missing = Literal["infer", "error"]
"""What a replay does with a field the game needs and the data lacks: fill it by rule, or fail."""
MISSING_CHOICES: tuple[Missing, ...] = ("infer", "error")

DEFAULT_PISTOL: dict[Side, str] = {"T": "Glock-18", "CT": "USP-S"}
"""The pistol each side starts with (the CT's default of the two offered; pros take the USP-S)."""
DEFAULT_RIFLE: dict[Side, str] = {"T": "AK-47", "CT": "M4A1"}
"""Each side's usual rifle (awpy's "M4A1" is the M4A1-S, the CT rifle of the real CS2 kills)."""
ECO_BUY_TYPES = ("Full Eco", "Semi Eco")
"""awpy buy types in which a side buys no primary weapon."""
FULL_ARMOR = 100
FIELD_NAMES = {"weapon": "weapon in hand", "armour": "armour, helmet and kit"}
"""The fields `lacking` names, in full where its short name is not (an error line)."""


@dataclass(frozen=True)
class Filled:
    """A round with its absent fields filled, and one note per filled field."""

    round: Round
    notes: tuple[str, ...]


def fill_missing(round_: Round, zones: SiteZones, rules: RulesConfig, missing: Missing) -> Filled:
    """The round with every absent field the game needs filled by the module's rules."""
    absent = lacking(round_)
    if missing == "error" and absent:
        raise EstaError(
            f"{round_.path}: round {round_.round_num}: the data lacks what the game needs "
            f"({', '.join(FIELD_NAMES.get(a, a) for a in absent)}); --missing-fields infer "
            "fills it by rule"
        )
    notes: list[str] = []
    weapon = _weapons(round_, notes)
    armor, helmet, kit = _equipment(round_, weapon, notes)
    filled = replace(round_, weapon=weapon, armor=armor, helmet=helmet, has_defuser=kit)
    if "bomb carrier" in absent:
        filled = _bomb(filled, zones, rules.plant_s, notes)
    if "defuser" in absent:
        filled = _defuse(filled, rules, notes)
    if "defuse start" in absent:
        filled = _defuse_start(filled, rules, notes)
    return Filled(filled, tuple(notes))


def lacking(round_: Round) -> tuple[str, ...]:
    """The fields the game needs that the round's data lacks, by name: what `fill_missing`
    fills (weapon and armour player by player) and `decoy info` shows."""
    weapon = np.asarray(round_.weapon, dtype=object) != ""
    armor = np.asarray(round_.armor) >= 0
    names = []
    if not weapon.any(axis=1).all():
        names.append("weapon")
    if not armor.any(axis=1).all():
        names.append("armour")
    carried = np.asarray(round_.has_bomb, bool).any() or _names_planter(round_)
    if not carried and _plant_tick(round_) is not None:
        names.append("bomb carrier")
    events = round_.bomb_events
    defused = len(events) and "bombAction" in events and (events["bombAction"] == "defuse").any()
    if round_.end_reason == "BombDefused" and not defused:
        names.append("defuser")
    if defused and len(_unstarted_defuses(events)):
        names.append("defuse start")
    return tuple(names)


def _unstarted_defuses(events: pd.DataFrame) -> pd.DataFrame:
    """The `defuse` events with no `defuse_start` at or before them."""
    starts = events.loc[events["bombAction"] == "defuse_start", "tick"].to_numpy(np.float64)
    defuses = events[events["bombAction"] == "defuse"]
    return defuses[[not (starts <= float(t)).any() for t in defuses["tick"]]]


def _firearm(name: object) -> bool:
    return name in FIREARMS


def _is_pistol(name: str) -> bool:
    return WEAPONS.get(name, ("", 0.0))[0] == "Pistols"


def _kills_by(round_: Round, name: str) -> pd.DataFrame:
    kills = round_.kills
    if len(kills) == 0 or "attackerName" not in kills or "weapon" not in kills:
        return kills.iloc[0:0]
    mine = kills[(kills["attackerName"] == name) & kills["weapon"].map(_firearm)]
    return mine.sort_values("tick", kind="stable")


def _side_weapon(round_: Round, side: Side) -> tuple[str, str]:
    """(weapon, rule) for a player of `side` without kills of his own."""
    kills = round_.kills
    if len(kills) and "attackerSide" in kills and "weapon" in kills:
        used = [w for w in kills.loc[kills["attackerSide"] == side, "weapon"] if _firearm(w)]
        if used:
            pistols = sum(_is_pistol(w) for w in used)
            if pistols * 2 > len(used):
                return DEFAULT_PISTOL[side], f"the {side} side's kills were mostly with pistols"
            rifles = Counter(w for w in used if WEAPONS[w][0] == "Rifle" and w != "AWP")
            rifle = rifles.most_common(1)[0][0] if rifles else DEFAULT_RIFLE[side]
            return rifle, f"the {side} side's kills were mostly with bought weapons"
    if is_pistol_round(round_.round_num, round_.tick_rate):
        return DEFAULT_PISTOL[side], "a pistol round"
    if round_.buy_types.get(side) in ECO_BUY_TYPES:
        return DEFAULT_PISTOL[side], f"the {side} side's buy type {round_.buy_types[side]}"
    return DEFAULT_RIFLE[side], f"the {side} side's usual rifle"


def _weapons(round_: Round, notes: list[str]) -> np.ndarray:
    weapon = np.asarray(round_.weapon, dtype=object).copy()
    rules: dict[str, list[str]] = {}
    ticks = np.asarray(round_.frame_ticks)
    for p, player in enumerate(round_.players):
        if any(weapon[p]):
            continue
        own = _kills_by(round_, player.name)
        if len(own):
            at = np.searchsorted(own["tick"].to_numpy(np.float64), ticks, side="left")
            names = own["weapon"].to_numpy(dtype=object)
            weapon[p] = names[np.minimum(at, len(names) - 1)]
            rule = "its own kills' weapons"
        else:
            weapon[p], why = _side_weapon(round_, player.side)
            rule = f"{weapon[p][0]}: {why}"
        rules.setdefault(rule, []).append(player.name)
    for rule, names in rules.items():
        notes.append(f"weapon in hand ({', '.join(names)}): {rule}")
    return weapon


def _equipment(
    round_: Round, weapon: np.ndarray, notes: list[str]
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    armor = np.asarray(round_.armor).copy()
    helmet = np.asarray(round_.helmet, bool).copy()
    kit = np.asarray(round_.has_defuser, bool).copy()
    pistol_round = is_pistol_round(round_.round_num, round_.tick_rate)
    kinds: dict[str, list[str]] = {}
    for p, player in enumerate(round_.players):
        if (armor[p] >= 0).any():
            continue
        first = next((str(w) for w in weapon[p] if w), "")
        buy = bool(first) and not _is_pistol(first)
        armor[p] = FULL_ARMOR if buy or pistol_round else 0
        helmet[p] = buy
        kit[p] = buy and player.side == "CT"
        kind = (
            "vest and helmet" + (" and kit" if kit[p].any() else "") + " (a buy)"
            if buy
            else ("vest (a pistol round)" if pistol_round else "no armour (an eco)")
        )
        kinds.setdefault(kind, []).append(player.name)
    for kind, names in kinds.items():
        notes.append(f"equipment ({', '.join(names)}): {kind}, by the weapon in hand")
    return armor, helmet, kit


def _plant_tick(round_: Round) -> float | None:
    return data_plant_tick(bomb_events(round_, []), round_)


def _names_planter(round_: Round) -> bool:
    """Whether the data's plant event says who planted (then nothing is inferred)."""
    events = bomb_events(round_, [])
    plants = events[events["bombAction"] == "plant"]
    if not len(plants):
        return False
    row = plants.iloc[0]
    name, steam_id = row.get("playerName"), row.get("playerSteamID")
    return (isinstance(name, str) and bool(name)) or not pd.isna(steam_id)


def _frame_at(ticks: np.ndarray, tick: float) -> int:
    """The last frame at or before `tick` (the first if none is)."""
    return int(np.clip(np.searchsorted(ticks, tick, side="right") - 1, 0, len(ticks) - 1))


def _bomb(round_: Round, zones: SiteZones, plant_s: float, notes: list[str]) -> Round:
    """The planter (module docstring); called when `lacking` names the bomb carrier."""
    tick = _plant_tick(round_)
    if tick is None or round_.clock is None:
        return round_
    ticks = np.asarray(round_.frame_ticks, dtype=np.float64)
    at = _frame_at(ticks, tick)
    alive = np.asarray(round_.alive, bool)[:, at]
    t_rows = [p for p, player in enumerate(round_.players) if player.side == "T" and alive[p]]
    if not t_rows:
        return round_  # named by `contradictions`
    site = _plant_site(round_)
    window = np.flatnonzero((ticks >= tick - plant_s * round_.clock.tick_rate) & (ticks <= tick))
    window = window if len(window) else np.array([at])
    position = np.asarray(round_.position, dtype=np.float64)
    steps = np.linalg.norm(np.diff(position[t_rows][:, window], axis=1), axis=2)
    moved = np.nan_to_num(steps, nan=np.inf).sum(axis=1)
    spots = position[t_rows, at]
    zone = zones.site_of(spots)
    order = np.lexsort((moved, zone == "", zone != site))
    planter = t_rows[int(order[0])]
    spot = spots[int(order[0])]
    where = f"in site {zone[order[0]]}" if zone[order[0]] else "in no site zone (none was)"
    events = round_.bomb_events
    if zone[order[0]] and site and zone[order[0]] != site:
        where += f" (the data names site {site}, where no T stood: site {zone[order[0]]} kept)"
        events = events.copy()
        events.loc[events["bombAction"] == "plant", "bombSite"] = str(zone[order[0]])
    has_bomb = np.zeros_like(np.asarray(round_.has_bomb, bool))
    has_bomb[planter, ticks < tick] = True
    has_bomb[planter] &= np.asarray(round_.alive, bool)[planter]
    bomb_position = np.asarray(round_.bomb_position, dtype=np.float64).copy()
    planted = np.asarray(round_.bomb_planted, bool) | (ticks >= tick)
    unknown = planted & ~np.isfinite(bomb_position).all(axis=1)
    bomb_position[unknown] = spot
    notes.append(
        f"bomb carrier and planter ({round_.players[planter].name}): the T alive at the plant "
        f"{where} who moved least over its {plant_s:g} s; carries from the start"
    )
    return replace(
        round_,
        has_bomb=has_bomb,
        bomb_position=bomb_position,
        bomb_planted=planted,
        bomb_events=events,
    )


def _plant_site(round_: Round) -> str:
    events = round_.bomb_events
    if len(events) and "bombSite" in events:
        sites = [s for s in events.loc[events["bombAction"] == "plant", "bombSite"] if s]
        if sites and isinstance(sites[0], str):
            return sites[0]
    named = [str(s) for s in np.asarray(round_.bombsite) if str(s)]
    return named[0] if named else ""


def _defuse(round_: Round, rules: RulesConfig, notes: list[str]) -> Round:
    """The defuser (module docstring); called when `lacking` names the defuser."""
    if round_.clock is None or round_.end_tick is None:
        return round_
    planted = np.flatnonzero(np.asarray(round_.bomb_planted, bool))
    if not len(planted):
        return round_  # named by `contradictions`
    bomb = np.asarray(round_.bomb_position, dtype=np.float64)[planted[0]]
    last = len(round_.frame_ticks) - 1
    alive = np.asarray(round_.alive, bool)[:, last]
    ct = [p for p, player in enumerate(round_.players) if player.side == "CT" and alive[p]]
    if not ct or not np.isfinite(bomb).all():
        return round_
    position = np.asarray(round_.position, dtype=np.float64)[ct, last]
    defuser = ct[int(np.argmin(np.linalg.norm(position - bomb, axis=1)))]
    kit = bool(np.asarray(round_.has_defuser, bool)[defuser].any())
    seconds = rules.defuse_kit_s if kit else rules.defuse_s
    start = round_.end_tick - seconds * round_.clock.tick_rate
    name = round_.players[defuser].name
    notes.append(
        f"defuse ({name}): the CT alive at the end nearest the bomb, from {seconds:g} s "
        f"before the round's end ({'with' if kit else 'without'} a kit)"
    )
    return _with_bomb_events(
        round_,
        [
            {"tick": start, "bombAction": "defuse_start", "playerName": name},
            {"tick": float(round_.end_tick), "bombAction": "defuse", "playerName": name},
        ],
    )


def _defuse_start(round_: Round, rules: RulesConfig, notes: list[str]) -> Round:
    """A `defuse_start` before each defuse the data has without one (module docstring)."""
    if round_.clock is None:
        return round_
    events = round_.bomb_events
    rows = []
    for defuse in _unstarted_defuses(events).itertuples():
        name = defuse.playerName if isinstance(defuse.playerName, str) else ""
        player = next((p for p, pl in enumerate(round_.players) if pl.name == name), -1)
        kit = player >= 0 and bool(np.asarray(round_.has_defuser, bool)[player].any())
        seconds = rules.defuse_kit_s if kit else rules.defuse_s
        start = float(defuse.tick) - seconds * round_.clock.tick_rate
        rows.append(
            {
                "tick": start,
                "bombAction": "defuse_start",
                "playerName": defuse.playerName,
                "playerSteamID": defuse.playerSteamID,
            }
        )
        notes.append(
            f"defuse start ({name or 'unnamed'}): {seconds:g} s before the data's defuse "
            f"({'with' if kit else 'without'} a kit)"
        )
    return _with_bomb_events(round_, rows) if rows else round_


def _with_bomb_events(round_: Round, rows: list[dict[str, object]]) -> Round:
    """The round with bomb events added (each on the round's clock), in tick order."""
    assert round_.clock is not None  # both callers return earlier without one
    added = pd.DataFrame(rows)
    added["seconds"] = round_.clock.seconds(added["tick"].to_numpy(np.float64))
    events = round_.bomb_events
    table = pd.concat([events, added], ignore_index=True) if len(events) else added
    return replace(
        round_, bomb_events=table.sort_values("tick", kind="stable").reset_index(drop=True)
    )


def contradictions(round_: Round) -> tuple[str, ...]:
    """What the frames and the events of a round say against each other (module docstring)."""
    found: list[str] = []
    names = {player.name: p for p, player in enumerate(round_.players)}
    ticks = np.asarray(round_.frame_ticks)
    alive = np.asarray(round_.alive, bool)
    kills = round_.kills
    dead_after: set[str] = set()
    if len(kills) and {"victimName", "attackerName", "tick"} <= set(kills.columns):
        for kill in kills.itertuples():
            victim, attacker = kill.victimName, kill.attackerName
            for who in (victim, attacker):
                if isinstance(who, str) and who and who not in names:
                    found.append(f"the kill at tick {kill.tick} names {who}, in no frame")
            if victim in names and not pd.isna(kill.tick):
                later = np.flatnonzero((ticks > float(kill.tick)) & alive[names[victim]])
                if len(later):
                    found.append(f"{victim} is alive at frame {later[0]}, after its kill")
                if ticks[-1] < float(kill.tick):
                    dead_after.add(victim)
    plant = _plant_tick(round_)
    if plant is not None and len(ticks):
        at = _frame_at(ticks, plant)
        if not any(alive[p, at] for p, pl in enumerate(round_.players) if pl.side == "T"):
            found.append("the bomb is planted with no T alive")
    if round_.end_reason == "BombDefused" and plant is None:
        found.append("the round ends BombDefused, but the bomb was never planted")
    if len(ticks) and round_.end_reason in ("CTWin", "TerroristsWin"):
        loser: Side = "T" if round_.end_reason == "CTWin" else "CT"
        standing = [
            pl.name
            for p, pl in enumerate(round_.players)
            if pl.side == loser and alive[p, -1] and pl.name not in dead_after
        ]
        if standing:
            found.append(
                f"the round ends {round_.end_reason}, yet {', '.join(standing)} of the "
                f"{loser} side are alive at its end"
            )
    return tuple(found)
