"""View angles an export filled in as "facing each other", drawn again as real views deviate.

An events-only export that did not record view angles may fill each damage and kill row's
attacker and victim views with the bearings that make the two face each other exactly
(`../shared/data/events_ancient` does, and says so). Taken as recorded, every hit of such a file
has a victim looking straight at his attacker, and a DIP learns that this is what a hit looks
like; real victims are often hit from the side (README, "Damage models"). A DIP trained on the
filled views then misses real hits whose victim looks elsewhere.

So a round whose every row between two enemies at different spots faces exactly (`filled_views`;
self-damage, such as a player in his own fire, has no facing to fill) has its views redrawn:
the facing bearing plus a deviation drawn from the real firearm hits' deviations
(`ATTACKER_DEVIATION_DEG`, `VICTIM_DEVIATION_DEG`: their quantiles over `hit_view_deviations`
of the de_dust2 events with real views, printed by `python benchmarks/studies/aim_study.py`),
seeded by the match and round so the samples are the same on every build.
"""

from __future__ import annotations

import zlib
from dataclasses import replace

import numpy as np
import pandas as pd

from decoy_cli.esta import Round
from decoy_cli.geometry import facing_yaw, wrap_180
from decoy_cli.modeling.sample_set import SampleStats
from decoy_cli.weapons import FIREARMS

FILLED_WITHIN_DEG = 0.01
"""A view this close to the facing bearing on every row was filled, not recorded."""
QUANTILES = np.linspace(0.0, 1.0, 21)
# fmt: off
ATTACKER_DEVIATION_DEG = np.array([
    -12.1, -1.9, -1.2, -0.9, -0.6, -0.5, -0.4, -0.3, -0.2, -0.1, 0.0,
    0.1, 0.2, 0.3, 0.4, 0.6, 0.8, 1.0, 1.3, 2.0, 4.1,
])
# fmt: on
"""Quantiles (`QUANTILES`) of the attacker's view minus his bearing of the victim, degrees,
over the real firearm hits between enemies of de_dust2's events (`hit_view_deviations`)."""
# fmt: off
VICTIM_DEVIATION_DEG = np.array([
    -161.5, -42.4, -13.0, -4.1, -1.8, -1.2, -0.8, -0.5, -0.2, -0.1, 0.1,
    0.3, 0.5, 0.7, 1.0, 1.7, 2.8, 5.9, 9.6, 24.0, 170.1,
])
# fmt: on
"""The same for the victim's view against his bearing of the attacker."""
TABLES = ("damages", "kills")
FILLED_NOTE = "view angles filled as facing each other: redrawn as real views deviate"
"""The `SampleStats.partial` key counting the rows redrawn."""


def _deviations(table: pd.DataFrame) -> tuple[np.ndarray, np.ndarray]:
    """(attacker, victim) view minus the facing bearing per row, degrees in [-180, 180)."""
    dx = (table["victimX_m"] - table["attackerX_m"]).to_numpy(np.float64)
    dy = (table["victimY_m"] - table["attackerY_m"]).to_numpy(np.float64)
    facing = facing_yaw(dx, dy)
    attacker = wrap_180(table["attackerViewX"].to_numpy(np.float64) - facing)
    victim = (table["victimViewX"].to_numpy(np.float64) - facing) % 360.0 - 180.0
    return attacker, victim


def hit_view_deviations(round_: Round) -> tuple[np.ndarray, np.ndarray]:
    """(attacker, victim) view deviations, degrees, of the round's firearm hits between enemies
    with both views: what `ATTACKER_DEVIATION_DEG` and `VICTIM_DEVIATION_DEG` summarise."""
    table = round_.damages
    if not _with_views(table) or not {"weapon", "attackerSide", "victimSide"} <= set(table):
        return np.zeros(0), np.zeros(0)
    rows, attacker, victim = _between_enemies(table[table["weapon"].isin(FIREARMS)])
    return attacker[rows], victim[rows]


def _between_enemies(table: pd.DataFrame) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(K,) rows whose attacker and victim are enemies at different spots with both views, and
    every row's (attacker, victim) view deviations (`_deviations`)."""
    attacker, victim = _deviations(table)
    apart = (table["victimX_m"] != table["attackerX_m"]) | (
        table["victimY_m"] != table["attackerY_m"]
    )
    rows = np.isfinite(attacker) & np.isfinite(victim) & apart.to_numpy(bool)
    if {"attackerSide", "victimSide"} <= set(table.columns):
        rows &= (table["attackerSide"] != table["victimSide"]).to_numpy(bool)
    return rows, attacker, victim


def _with_views(table: pd.DataFrame) -> bool:
    columns = {f"{who}{part}" for who in ("attacker", "victim") for part in ("X_m", "Y_m", "ViewX")}
    return len(table) > 0 and columns <= set(table.columns)


def filled_views(round_: Round) -> int:
    """The round's damage and kill rows between enemies at different spots with both views when
    every one of them faces exactly (a recorded victim's view almost never does); 0 when one
    does not, or there is none."""
    rows = 0
    for name in TABLES:
        table = getattr(round_, name)
        if not _with_views(table):
            continue
        known, attacker, victim = _between_enemies(table)
        if np.abs(np.concatenate([attacker[known], victim[known]])).max(initial=0.0) > (
            FILLED_WITHIN_DEG
        ):
            return 0
        rows += int(known.sum())
    return rows


def redraw_filled_views(round_: Round, stats: SampleStats) -> Round:
    """The round with filled views redrawn (module docstring), counted in `stats.partial`;
    unchanged when its views were recorded."""
    filled = filled_views(round_)
    if not filled:
        return round_
    seed = [zlib.crc32(str(round_.match_id).encode()), int(round_.round_num)]
    rng = np.random.default_rng(seed)
    tables = {}
    for name in TABLES:
        table = getattr(round_, name)
        if not _with_views(table):
            continue
        table = table.copy()
        draws = rng.random((len(table), 2))
        table["attackerViewX"] += np.interp(draws[:, 0], QUANTILES, ATTACKER_DEVIATION_DEG)
        table["victimViewX"] += np.interp(draws[:, 1], QUANTILES, VICTIM_DEVIATION_DEG)
        tables[name] = table
    stats.partial[FILLED_NOTE] += filled
    return replace(round_, **tables)
