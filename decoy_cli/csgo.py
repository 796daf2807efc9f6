"""CS:GO facts the whole project shares: units, player dimensions, movement limits.

Most names here are game rules (values of the game). The few marked "project choice" are not:
they are how this project models the player (the simulated capsule), kept here so the waypoint
builder, which verifies edges with that capsule, and the simulator, which moves it, share them.

Everything inside the project is in metres (x east, y north, z up, as in the Source engine);
Hammer units are converted once where data enters (the ESTA reader, the nav assets, user meshes).
"""

from __future__ import annotations

import math

MAP_NAMES = (
    "de_ancient",
    "de_dust2",
    "de_inferno",
    "de_mirage",
    "de_nuke",
    "de_overpass",
    "de_train",
    "de_vertigo",
)
"""The eight competitive maps ESTA covers; each ships its world and waypoint graph."""

BUILTIN_MAP = "de_dust2"
"""The default map of every command (the one the real data in ../shared/data is on)."""

HAMMER_TO_M = 0.01905
"""One Hammer unit in metres."""

PLAYER_RADIUS_M = 16 * HAMMER_TO_M
"""Half the width of the 32 x 32 u standing player hull."""

PLAYER_HEIGHT_M = 72 * HAMMER_TO_M
"""Standing hull height."""

EYE_HEIGHT_M = 64 * HAMMER_TO_M
"""Standing eye height above the feet."""

STEP_HEIGHT_M = 18 * HAMMER_TO_M
"""Highest ledge a player walks up without jumping (sv_stepsize 18)."""

AGENT_RADIUS_M = 0.8 * PLAYER_RADIUS_M
"""Project choice: radius of the simulated agent's capsule, 20% thinner than the player hull,
because the nav world's walls are approximate (see `decoy_cli.waypoints.lattice`)."""

AGENT_FLOAT_CLEARANCE_M = 0.03
"""Project choice: how far above the step height the agent's capsule floats, so that it passes
ledges of exactly the step height."""

AGENT_FLOAT_M = STEP_HEIGHT_M + AGENT_FLOAT_CLEARANCE_M
"""Project choice: height of the bottom of the agent's capsule above its feet (a dynamic
capsule cannot climb steps; a floating one moved kinematically passes over them)."""

AGENT_GRAZE_M = 0.025
"""Project choice: how deep the agent's capsule may penetrate the world (the walls are
approximate)."""

JUMP_HEIGHT_M = 65 * HAMMER_TO_M
"""Highest block a player gets onto with a crouch-jump: 65 u (Valve Developer Community, CS:GO
Mapper's Reference, "Reachable Heights": crouch then jump 65, a plain jump 54). Maps build 64 u
crates because a crouch-jump clears them."""

GRAVITY_U_S2 = 800.0
"""sv_gravity: downward acceleration in Hammer units per second squared."""

SAFE_FALL_SPEED_U_S = 580.0
"""Landing speed up to which a fall does no damage (CS_PLAYER_MAX_SAFE_FALL_SPEED in CS:GO's
cs_gamerules.cpp): a fall of 580² / (2 × 800) = 210 u."""

FATAL_FALL_SPEED_U_S = 1000.0
"""Landing speed at which a fall does 100 damage (CS_PLAYER_FATAL_FALL_SPEED in CS:GO's
cs_gamerules.cpp; the Source SDK's 1024 and Counter-Strike: Source's 1100 x 1.25 are other
games'). The damage is linear in between. On the real T-side rounds, health lost at falls of
200-310 u follows it (`python benchmarks/studies/fall_damage_check.py`)."""

SAFE_DROP_M = SAFE_FALL_SPEED_U_S**2 / (2 * GRAVITY_U_S2) * HAMMER_TO_M
"""The deepest fall that does no damage (210 u)."""

MAX_DROP_M = 620 * HAMMER_TO_M
"""Project choice: the deepest drop the waypoint builder links, a fall a player at full health
survives (99 damage; 625 u is fatal). Drops deeper than `SAFE_DROP_M` cost health
(`fall_damage`)."""

MAX_VELOCITY_M_S = 3500 * HAMMER_TO_M
"""The engine's velocity cap (sv_maxvelocity 3500 u/s): no player moves faster, falling included."""

TICK_RATE = 60
"""Physics ticks per second of the simulator."""

GRAVITY_M_S2 = GRAVITY_U_S2 * HAMMER_TO_M
"""Gravity (sv_gravity 800 u/s²) in metres."""

JUMP_SPEED_M_S = 301.99 * HAMMER_TO_M
"""Upward speed a jump starts with (sqrt(2 * 800 * 57) u/s): a plain jump rises about 57 u."""

LADDER_SPEED_M_S = 200 * 0.78 * HAMMER_TO_M
"""Climbing speed on a ladder: the Source engine's MAX_CLIMB_SPEED (200 u/s) scaled by CS:GO's
sv_ladder_scale_speed (0.78 by default), 156 u/s, up or down."""


def seconds_to_ticks(seconds: float, tick_rate: int = TICK_RATE) -> int:
    """A duration as a whole number of ticks, rounded up so that no rule runs shorter than in the
    game. The product is first rounded to 1e-6, so float noise adds no tick: 8.3 * 60 is
    498.00000000000006 and gives 498, not 499."""
    return math.ceil(round(seconds * tick_rate, 6))


def tick_at(seconds: float, tick_rate: int = TICK_RATE) -> int:
    """The tick nearest a moment in time (seconds on the round's clock): where data frames,
    deadlines and recorded events fall."""
    return round(float(seconds) * tick_rate)


def fall_damage(height_m: float) -> int:
    """Damage of a fall from rest through `height_m` metres: the landing speed at sv_gravity 800
    above the safe speed, times 100 / (fatal − safe), rounded to whole health points."""
    speed_u_s = math.sqrt(2 * GRAVITY_U_S2 * max(height_m, 0.0) / HAMMER_TO_M)
    if speed_u_s <= SAFE_FALL_SPEED_U_S:
        return 0
    per_speed = 100 / (FATAL_FALL_SPEED_U_S - SAFE_FALL_SPEED_U_S)
    return round((speed_u_s - SAFE_FALL_SPEED_U_S) * per_speed)


def is_pistol_round(round_num: int, tick_rate: int) -> bool:
    """Round 1 and the first of the second half: 13 in CS2's MR12 (its demos run at 64 ticks),
    16 in CS:GO's MR15. Its $800 start money buys a vest ($650), not a vest and helmet ($1000)."""
    return round_num in ((1, 13) if tick_rate == 64 else (1, 16))
