"""Help of options shared by several commands: the maps, who decides deaths, and what to do
with the fields the data lacks (the last two are `Literal` types, which Typer lists)."""

from __future__ import annotations

from decoy_cli.csgo import MAP_NAMES

MAPS_HELP = "one of " + ", ".join(m.removeprefix("de_") for m in MAP_NAMES) + " (de_ optional)"
"""The built-in maps, for the help of every `--map`."""

DEATHS_HELP = (
    "Who decides deaths when shooting: simulated (the fight; a player the data shows dead whom "
    "the fight has not killed within 3 s of his real death is taken out then, counted as not "
    "reproduced) or data (the paper's protocol: a player dies when the data says so; shooting "
    "wounds but does not kill). Without shooting, deaths come from the data either way."
)
SIGHT_MESH_HELP = (
    "The map's geometry to test line of sight in when shooting: a triangle mesh in Hammer units, "
    "z up (awpy's .tri, or an .obj). Default: the nav world the graph was built on, which lacks "
    "windows, props and low cover."
)
MISSING_HELP = (
    "Fields the game needs and the data lacks (weapon in hand, armour, the bomb's carrier, the "
    "defuser): infer (filled by the rules of decoy_cli/replay/missing.py and named per round "
    "in the outputs) or error (the round fails)."
)
MOVER_HELP = (
    "kinematic (compiled motion along the graph's edges, agents pass through each other; "
    "measured the more faithful in replays) or physics (pybullet capsules that block each "
    "other, as the paper's engine)"
)
