"""Options shared by several commands, each defined once: how a round runs (`RunOptions`, the
group `decoy replay` and `decoy evaluate` share), the mover and the damage models for the other
commands, and the help of the maps (the mover, deaths, missing fields and implausible data are
`Literal` types, which Typer lists)."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Annotated

import typer

from decoy_cli.csgo import MAP_NAMES
from decoy_cli.damage import CHOICES_HELP, DEFAULT_MODELS
from decoy_cli.damage.choice import MODELS_METAVAR, ModelName
from decoy_cli.esta.plausibility import Implausible
from decoy_cli.replay.deaths import DeathProtocol
from decoy_cli.replay.missing import Missing
from decoy_cli.sim.setup import MoverName

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
IMPLAUSIBLE_HELP = (
    "Rounds with implausible data (README: what the reader and the replay refuse): fail (a "
    "recorded failure) or warn (replayed anyway, their warnings named in the outputs)."
)
MOVER_HELP = (
    "kinematic (compiled motion along the graph's edges, agents pass through each other; "
    "measured the more faithful in replays) or physics (pybullet capsules that block each "
    "other, as the paper's engine)"
)


def mover_option(default: MoverName) -> MoverName:
    """The `--mover` option (Typer's parameter default), `default` unless told."""
    return typer.Option(default, "--mover", help=f"The mover: {MOVER_HELP}.")


MODELS_HELP = f"The damage models when shooting: {CHOICES_HELP}."


def models_option(default: ModelName) -> str:
    """The `--models` option (Typer's parameter default), `default` unless told: its text, which
    the command parses once (`decoy_cli.damage.parse_models`)."""
    return typer.Option(default.value, "--models", metavar=MODELS_METAVAR, help=MODELS_HELP)


@dataclass(frozen=True)
class RunOptions:
    """How `decoy replay` and `decoy evaluate` run a round: shooting and its models, the bomb,
    the mover, who decides deaths, what to do with missing fields and implausible data, the
    geometry of sight, and the seed."""

    combat: Annotated[
        bool,
        typer.Option(
            "--combat/--no-combat",
            help="Shooting, with the damage models of --models; without it deaths are scripted "
            "from the data. The paper's movement-only Table 2 is --no-combat --no-bomb.",
        ),
    ] = True
    bomb: Annotated[
        bool,
        typer.Option("--bomb/--no-bomb", help="Bomb rules: carrier, plant, defuse, detonation."),
    ] = True
    models: Annotated[str, typer.Option("--models", metavar=MODELS_METAVAR, help=MODELS_HELP)] = (
        DEFAULT_MODELS.value
    )
    mover: Annotated[MoverName, typer.Option("--mover", help=f"The mover: {MOVER_HELP}.")] = (
        "kinematic"
    )
    deaths: Annotated[DeathProtocol, typer.Option("--deaths", help=DEATHS_HELP)] = "simulated"
    missing: Annotated[Missing, typer.Option("--missing-fields", help=MISSING_HELP)] = "infer"
    implausible: Annotated[Implausible, typer.Option("--implausible", help=IMPLAUSIBLE_HELP)] = (
        "fail"
    )
    sight_mesh: Annotated[Path | None, typer.Option("--sight-mesh", help=SIGHT_MESH_HELP)] = None
    seed: Annotated[
        int,
        typer.Option(
            "--seed", help="Seed of the simulator's random numbers (and of evaluate's --sample)."
        ),
    ] = 0
