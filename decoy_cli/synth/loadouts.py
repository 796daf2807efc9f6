"""What each player buys in a scripted round: weapons, armor, helmet, defuse kit.

A small economy that gives plausible rounds without modelling money: the first round of each
half is a pistol round; the round after it, the side that lost saves (eco) and the side that won
plays with what it picked up (a force buy); later rounds draw a full buy (70%), a force buy (15%)
or an eco (15%) per side. Prices are CS:GO's, for the team equipment values and buy types the
file reports. Weapon names are awpy's (decoy_cli/weapons.py).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from decoy_cli.weapons import WEAPONS

PRICES = {
    "Glock-18": 200,
    "USP-S": 200,
    "P2000": 200,
    "P250": 300,
    "Tec-9": 500,
    "Five-SeveN": 500,
    "Desert Eagle": 700,
    "MAC-10": 1050,
    "MP9": 1250,
    "UMP-45": 1200,
    "Galil AR": 1800,
    "FAMAS": 2050,
    "AK-47": 2700,
    "M4A1": 2900,
    "M4A4": 3100,
    "AWP": 4750,
}
"""Prices of the weapons the loadouts use, dollars (the default pistols count as 200, as in
awpy's equipment values)."""

KEVLAR = 650
KEVLAR_HELMET = 1000
DEFUSE_KIT = 400
DEFAULT_PISTOL = {"T": "Glock-18", "CT": "USP-S"}
START_VALUE = 200
"""Equipment value at the round start: the default pistol (what the real files show for a
side of five that saved nothing: 1,000)."""

BUY_KINDS = ("pistol", "eco", "force", "full")
_LATER_BUYS = (("full", 0.70), ("force", 0.15), ("eco", 0.15))
_PISTOLS = {
    "T": (("Glock-18", 0.6), ("P250", 0.2), ("Tec-9", 0.2)),
    "CT": (("USP-S", 0.5), ("P2000", 0.3), ("P250", 0.1), ("Five-SeveN", 0.1)),
}
_FORCE = {
    "T": (("Galil AR", 0.5), ("MAC-10", 0.3), ("Tec-9", 0.2)),
    "CT": (("FAMAS", 0.5), ("MP9", 0.3), ("UMP-45", 0.2)),
}
_RIFLES = {"T": (("AK-47", 1.0),), "CT": (("M4A4", 0.6), ("M4A1", 0.4))}
_AWP_CHANCE = {"T": 0.5, "CT": 0.6}
_FULL_BUY_KITS = 3
_FREE_PISTOLS = frozenset({"Glock-18", "USP-S", "P2000"})


@dataclass(frozen=True)
class Loadout:
    """One player's equipment: `active` is the weapon in hand (the primary if any)."""

    pistol: str
    primary: str | None
    armor: int
    helmet: bool
    defuse_kit: bool

    @property
    def active(self) -> str:
        return self.primary or self.pistol

    @property
    def inventory(self) -> tuple[str, ...]:
        """Weapons held, as awpy lists them (knife included)."""
        return (*(() if self.primary is None else (self.primary,)), self.pistol, "Knife")

    @property
    def value(self) -> int:
        """Equipment value in dollars."""
        armor = (KEVLAR_HELMET if self.helmet else KEVLAR) if self.armor else 0
        primary = PRICES[self.primary] if self.primary else 0
        return PRICES[self.pistol] + primary + armor + (DEFUSE_KIT if self.defuse_kit else 0)


def buy_kind(
    round_index: int, side: str, previous_winner: str | None, half: int, rng: np.random.Generator
) -> str:
    """The buy of a side in the round at 0-based `round_index` of a half of `half` rounds."""
    position = round_index % half
    if position == 0:
        return "pistol"
    if position == 1 and previous_winner is not None:
        return "force" if previous_winner == side else "eco"
    names = [name for name, _ in _LATER_BUYS]
    weights = [weight for _, weight in _LATER_BUYS]
    return str(rng.choice(names, p=weights))


def side_loadouts(side: str, kind: str, count: int, rng: np.random.Generator) -> list[Loadout]:
    """The loadouts of `count` players of one side for a buy kind (see BUY_KINDS)."""
    if kind not in BUY_KINDS:
        raise ValueError(f"unknown buy kind {kind!r} ({', '.join(BUY_KINDS)})")
    out = []
    awp = int(rng.integers(count)) if kind == "full" and rng.random() < _AWP_CHANCE[side] else -1
    kits = set(rng.choice(count, size=min(_FULL_BUY_KITS, count), replace=False).tolist())
    for k in range(count):
        if kind == "pistol":  # $800: a default pistol and kevlar, or a better pistol (or a kit)
            pistol = _draw(_PISTOLS[side], rng)
            armored = pistol in _FREE_PISTOLS and rng.random() < 0.6
            kit = side == "CT" and not armored and k in kits
            out.append(Loadout(pistol, None, 100 if armored else 0, False, kit))
        elif kind == "eco":
            pistol = DEFAULT_PISTOL[side] if rng.random() < 0.7 else "P250"
            out.append(Loadout(pistol, None, 0, False, False))
        elif kind == "force":
            choice = _draw(_FORCE[side], rng)
            if WEAPONS[choice][0] == "Pistols":
                out.append(Loadout(choice, None, 100, False, False))
            else:
                out.append(
                    Loadout(DEFAULT_PISTOL[side], choice, 100, False, side == "CT" and k == 0)
                )
        else:
            primary = "AWP" if k == awp else _draw(_RIFLES[side], rng)
            kit = side == "CT" and k in kits
            out.append(Loadout(DEFAULT_PISTOL[side], primary, 100, True, kit))
    return out


def _draw(choices: tuple[tuple[str, float], ...], rng: np.random.Generator) -> str:
    names, weights = zip(*choices, strict=True)
    return str(rng.choice(names, p=weights))
