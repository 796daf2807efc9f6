"""CS:GO weapons as awpy 1.x names them: class and maximum running speed.

Names are the display names found in ESTA frames (`activeWeapon`) and events (`weapon`). Speeds
are the CS:GO maximum ground speeds in units per second with the weapon in hand (knife 250);
a plan that asks a player to cover more ground per frame than this is physically impossible.
"""

from __future__ import annotations

from decoy_cli.csgo import HAMMER_TO_M
from decoy_cli.errors import EstaError

# name: (awpy weaponClass, max speed u/s)
WEAPONS: dict[str, tuple[str, float]] = {
    # pistols
    "Glock-18": ("Pistols", 240.0),
    "USP-S": ("Pistols", 240.0),
    "P2000": ("Pistols", 240.0),
    "P250": ("Pistols", 240.0),
    "Dual Berettas": ("Pistols", 240.0),
    "Five-SeveN": ("Pistols", 240.0),
    "Tec-9": ("Pistols", 240.0),
    "CZ75 Auto": ("Pistols", 240.0),
    "Desert Eagle": ("Pistols", 230.0),
    "R8 Revolver": ("Pistols", 220.0),
    # SMGs
    "MAC-10": ("SMG", 240.0),
    "MP9": ("SMG", 240.0),
    "MP7": ("SMG", 220.0),
    "MP5-SD": ("SMG", 235.0),
    "UMP-45": ("SMG", 230.0),
    "P90": ("SMG", 230.0),
    "PP-Bizon": ("SMG", 240.0),
    # rifles (awpy calls the M4A1-S "M4A1")
    "AK-47": ("Rifle", 215.0),
    "M4A4": ("Rifle", 225.0),
    "M4A1": ("Rifle", 225.0),
    "Galil AR": ("Rifle", 215.0),
    "FAMAS": ("Rifle", 220.0),
    "SG 553": ("Rifle", 210.0),
    "AUG": ("Rifle", 220.0),
    "SSG 08": ("Rifle", 230.0),
    "AWP": ("Rifle", 200.0),
    "G3SG1": ("Rifle", 215.0),
    "SCAR-20": ("Rifle", 215.0),
    # heavy
    "Nova": ("Heavy", 220.0),
    "XM1014": ("Heavy", 215.0),
    "MAG-7": ("Heavy", 225.0),
    "Sawed-Off": ("Heavy", 210.0),
    "M249": ("Heavy", 195.0),
    "Negev": ("Heavy", 150.0),
    # grenades
    "HE Grenade": ("Grenade", 245.0),
    "Flashbang": ("Grenade", 245.0),
    "Smoke Grenade": ("Grenade", 245.0),
    "Decoy Grenade": ("Grenade", 245.0),
    "Molotov": ("Grenade", 245.0),
    "Incendiary Grenade": ("Grenade", 245.0),
    # equipment
    "Knife": ("Equipment", 250.0),
    "C4": ("Equipment", 250.0),
    "Zeus x27": ("Equipment", 220.0),
}

FIREARMS = tuple(
    name for name, (kind, _) in WEAPONS.items() if kind in ("Pistols", "SMG", "Rifle", "Heavy")
)
"""The weapons that shoot bullets (what the damage models know)."""

NO_WEAPON = ""
"""awpy writes an empty `activeWeapon` between weapon switches and for dead players."""

KNIFE_SPEED = 250.0


def is_known(name: str) -> bool:
    """True for a name in the table or the empty name."""
    return name == NO_WEAPON or name in WEAPONS


def max_speed_u_s(name: str) -> float:
    """Maximum running speed with this weapon in hand, Hammer units per second.

    The empty name (no weapon in hand) runs at knife speed. Unknown names raise EstaError.
    """
    if name == NO_WEAPON:
        return KNIFE_SPEED
    try:
        return WEAPONS[name][1]
    except KeyError:
        raise EstaError(f"unknown weapon {name!r}") from None


def max_speed_m_s(name: str) -> float:
    """Maximum running speed with this weapon in hand, metres per second."""
    return max_speed_u_s(name) * HAMMER_TO_M
