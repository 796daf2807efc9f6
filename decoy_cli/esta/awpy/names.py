"""awpy's names for weapons, hit groups, sides, round end reasons and bomb events, as ESTA (awpy
1.x, decoy_cli/weapons.py) names them: the one table between the sources.

A weapon has three spellings besides ESTA's: demoparser2's display names (awpy 2's tick column
`active_weapon_name`: "M4A1-S", "CZ75-Auto", "C4 Explosive"), the game's item names (awpy 2 and
awpy 3 events and awpy 3 snapshots: "m4a1_silencer", "cz75a"; shots add "weapon_"), and ESTA's
("M4A1" is the M4A1-S there). The look-alikes stay apart wherever the source tells them apart:
M4A4 `m4a1` / M4A1-S `m4a1_silencer`, P2000 `hkp2000` / USP-S `usp_silencer`, Desert Eagle
`deagle` / R8 `revolver`. A name in none of the tables is `None` here and a named warning of the
round (decoy_cli/esta/awpy/rounds.py), never a silent default.
"""

from __future__ import annotations

from typing import Literal

Spelling = Literal["display", "item"]

# ESTA name: (demoparser2 display names, game item names)
WEAPON_SPELLINGS: dict[str, tuple[tuple[str, ...], tuple[str, ...]]] = {
    "Glock-18": (("Glock-18",), ("glock",)),
    "USP-S": (("USP-S",), ("usp_silencer",)),
    "P2000": (("P2000",), ("hkp2000",)),
    "P250": (("P250",), ("p250",)),
    "Dual Berettas": (("Dual Berettas",), ("elite",)),
    "Five-SeveN": (("Five-SeveN",), ("fiveseven",)),
    "Tec-9": (("Tec-9",), ("tec9",)),
    "CZ75 Auto": (("CZ75-Auto",), ("cz75a",)),
    "Desert Eagle": (("Desert Eagle",), ("deagle",)),
    "R8 Revolver": (("R8 Revolver",), ("revolver",)),
    "MAC-10": (("MAC-10",), ("mac10",)),
    "MP9": (("MP9",), ("mp9",)),
    "MP7": (("MP7",), ("mp7",)),
    "MP5-SD": (("MP5-SD",), ("mp5sd",)),
    "UMP-45": (("UMP-45",), ("ump45",)),
    "P90": (("P90",), ("p90",)),
    "PP-Bizon": (("PP-Bizon",), ("bizon",)),
    "AK-47": (("AK-47",), ("ak47",)),
    "M4A4": (("M4A4",), ("m4a1",)),
    "M4A1": (("M4A1-S",), ("m4a1_silencer",)),
    "Galil AR": (("Galil AR",), ("galilar",)),
    "FAMAS": (("FAMAS",), ("famas",)),
    "SG 553": (("SG 553",), ("sg556",)),
    "AUG": (("AUG",), ("aug",)),
    "SSG 08": (("SSG 08",), ("ssg08",)),
    "AWP": (("AWP",), ("awp",)),
    "G3SG1": (("G3SG1",), ("g3sg1",)),
    "SCAR-20": (("SCAR-20", "Scar-20"), ("scar20",)),
    "Nova": (("Nova",), ("nova",)),
    "XM1014": (("XM1014",), ("xm1014",)),
    "MAG-7": (("MAG-7",), ("mag7",)),
    "Sawed-Off": (("Sawed-Off",), ("sawedoff",)),
    "M249": (("M249",), ("m249",)),
    "Negev": (("Negev",), ("negev",)),
    "HE Grenade": (("High Explosive Grenade",), ("hegrenade",)),
    "Flashbang": (("Flashbang",), ("flashbang",)),
    "Smoke Grenade": (("Smoke Grenade",), ("smokegrenade",)),
    "Decoy Grenade": (("Decoy Grenade",), ("decoy",)),
    "Molotov": (("Molotov",), ("molotov",)),
    # a fire's damage names no grenade ("inferno"); ESTA's CS2 rounds call it an incendiary
    "Incendiary Grenade": (("Incendiary Grenade",), ("incendiary", "incgrenade", "inferno")),
    "Knife": (("Knife", "knife", "knife_t"), ("knife", "knife_t", "bayonet")),
    "C4": (("C4 Explosive", "C4"), ("c4", "planted_c4")),
    "Zeus x27": (("Zeus x27",), ("taser",)),
    "World": ((), ("world",)),
}
"""Every weapon by its ESTA name: its display and item spellings."""

KNIFE_PREFIXES = ("knife", "weapon_knife", "Knife")
"""Knives come in dozens of skins ("knife_karambit", "Karambit"... "Butterfly Knife"); every
one is a knife to the game."""

_BY_SPELLING: dict[Spelling, dict[str, str]] = {
    "display": {s: esta for esta, (shown, _) in WEAPON_SPELLINGS.items() for s in shown},
    "item": {s: esta for esta, (_, items) in WEAPON_SPELLINGS.items() for s in items},
}


def weapon_name(raw: object, spelling: Spelling) -> str | None:
    """The ESTA name of a weapon as a source spells it; "" for no weapon (null or empty);
    None for a name in no table."""
    if raw is None or raw == "":
        return ""
    if not isinstance(raw, str):
        return None
    name = raw.removeprefix("weapon_")
    found = _BY_SPELLING[spelling].get(name)
    if found is not None:
        return found
    if name.startswith(KNIFE_PREFIXES) or name.endswith((" Knife", "Bayonet", "Daggers")):
        return "Knife"
    return None


HIT_GROUPS = {
    "generic": "Generic",
    "head": "Head",
    "chest": "Chest",
    "stomach": "Stomach",
    "left_arm": "LeftArm",
    "right_arm": "RightArm",
    "left_leg": "LeftLeg",
    "right_leg": "RightLeg",
    "neck": "Neck",
}
"""awpy's hit group names (awpy 2's strings, awpy 3's `hitgroup_name`) as ESTA's."""

HIT_GROUP_CODES = dict(enumerate(HIT_GROUPS))
"""awpy 3's `hitgroup` numbers: 0 generic ... 7 right leg, 8 neck."""

NO_HIT_GROUP = frozenset({"-1", "invalid", "gear", "9", "unused", "11", "special"})
"""Hit groups awpy names that are not a part of the body ESTA knows: left unrecorded."""


def hit_group(raw: object) -> str | None:
    """ESTA's hit group of awpy's name or number; "" where awpy records none; None unknown."""
    if raw is None:
        return ""
    if isinstance(raw, int | float) and not isinstance(raw, bool):
        raw = HIT_GROUP_CODES.get(int(raw), str(int(raw)))
    if not isinstance(raw, str):
        return None
    if raw in NO_HIT_GROUP:
        return ""
    return HIT_GROUPS.get(raw)


SIDES = {
    "t": "T",
    "ct": "CT",
    "T": "T",
    "CT": "CT",
    "terrorist": "T",
    "counter-terrorist": "CT",
    "TERRORIST": "T",
    2: "T",
    3: "CT",
}
"""awpy 2's `t`/`ct` (`T` for a T win in awpy 2.0.0-2.0.1), awpy 3's `terrorist`/
`counter-terrorist` and `rounds.winner` 2/3."""


def side_name(raw: object) -> str | None:
    """ "T" or "CT" for awpy's side; None for anything else (a spectator, a draw)."""
    if isinstance(raw, float) and raw == int(raw):
        raw = int(raw)
    return SIDES.get(raw) if isinstance(raw, str | int) else None


END_REASONS = {
    # awpy 2 (demoparser2's names)
    "bomb_exploded": "TargetBombed",
    "bomb_defused": "BombDefused",
    "t_killed": "CTWin",
    "ct_killed": "TerroristsWin",
    "time_ran_out": "TargetSaved",
    "draw": "Draw",
    "t_surrender": "TerroristsSurrender",
    "ct_surrender": "CTSurrender",
    # awpy 3 (`reason_name`)
    "target_bombed": "TargetBombed",
    "ct_win": "CTWin",
    "terrorists_win": "TerroristsWin",
    "target_saved": "TargetSaved",
    "terrorists_surrender": "TerroristsSurrender",
}
"""awpy's round end reasons as awpy 1.x (ESTA) names them."""

END_REASON_CODES = {1: "TargetBombed", 7: "BombDefused", 8: "CTWin", 9: "TerroristsWin"}
END_REASON_CODES |= {10: "Draw", 12: "TargetSaved", 17: "TerroristsSurrender", 18: "CTSurrender"}
"""awpy 3's `reason` numbers (the game's round win reasons)."""


def end_reason(raw: object) -> str | None:
    """ESTA's round end reason of awpy's name or number; None for one in no table."""
    if isinstance(raw, int | float) and not isinstance(raw, bool):
        return END_REASON_CODES.get(int(raw))
    return END_REASONS.get(raw) if isinstance(raw, str) else None


BOMB_ACTIONS = {
    # awpy 2
    "plant": "plant",
    "defuse": "defuse",
    "detonate": "explode",
    # awpy 3
    "start_plant": "plant_begin",
    "interrupt_plant": "plant_abort",
    "finish_plant": "plant",
}
"""awpy's bomb events as ESTA's `bombAction`; "drop" and "pickup" have none (they move the
carrier, which the tick tables give)."""
CARRIER_EVENTS = frozenset({"drop", "pickup"})


def bomb_action(raw: object) -> str | None:
    """ESTA's bomb action of awpy's event; None for an event ESTA does not list."""
    return BOMB_ACTIONS.get(raw) if isinstance(raw, str) else None


def bomb_site(raw: object) -> str:
    """ "A" or "B" from awpy's site ("bombsite_a", "BombsiteB", "A", "bombsite a"); "" else."""
    if not isinstance(raw, str):
        return ""
    text = raw.lower().replace("_", "").replace(" ", "")
    if text in ("a", "bombsitea"):
        return "A"
    if text in ("b", "bombsiteb"):
        return "B"
    return ""
