"""Options shared by several commands, each defined once: how a round runs (`RunOptions`, the
group `decoy replay` and `decoy evaluate` share), how damage samples are read and split
(`SampleOptions`, for `decoy train` and `decoy models`), the mover and the damage models for the
other commands, and the help of the maps (the mover, deaths, missing fields and implausible data are
`Literal` types, which Typer lists)."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Annotated

import typer

from decoy_cli.csgo import MAP_NAMES
from decoy_cli.damage import CHOICES_HELP, DEFAULT_MODELS
from decoy_cli.damage.choice import MODELS_METAVAR, ModelName
from decoy_cli.esta.plausibility import Implausible
from decoy_cli.modeling.provenance import SampleChoice
from decoy_cli.modeling.samples import DEFAULT_MODE, DEFAULT_WINDOW_S, SampleMode
from decoy_cli.modeling.split import (
    DEFAULT_SEED,
    DEFAULT_SPLIT,
    DEFAULT_TEST_FRACTION,
    DEFAULT_VAL_FRACTION,
    SplitUnit,
)
from decoy_cli.replay.deaths import DeathProtocol
from decoy_cli.replay.missing import Missing
from decoy_cli.replay.replayer import ReplaySpec
from decoy_cli.sim.setup import MoverName
from decoy_cli.waypoints.build import GameWorld

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
    "z up (awpy's .tri, awpy 3's .mesh, or an .obj). Default: the nav world the graph was built "
    "on, which lacks windows, props and low cover."
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


WORLD_HELP = (
    "The world to replay on without --graph: CS:GO's (csgo), or CS2's (cs2, shipped for "
    "de_dust2: movement closer to CS2 data, the real winner less often with the fight "
    "deciding; docs/cs2.md)."
)


def world_option(help_text: str = WORLD_HELP) -> GameWorld:
    """The `--world` option (Typer's parameter default)."""
    return typer.Option("csgo", "--world", help=help_text)


def mover_option(default: MoverName) -> MoverName:
    """The `--mover` option (Typer's parameter default), `default` unless told."""
    return typer.Option(default, "--mover", help=f"The mover: {MOVER_HELP}.")


MODELS_HELP = f"The damage models when shooting: {CHOICES_HELP}."


def models_option(default: ModelName) -> str:
    """The `--models` option (Typer's parameter default), `default` unless told: its text, which
    the command parses once (`decoy_cli.damage.parse_models`)."""
    return typer.Option(default.value, "--models", metavar=MODELS_METAVAR, help=MODELS_HELP)


RATE_HELP = (
    "Frames a second read from awpy's full-rate ticks (default 8, docs/cs2.md); data sampled "
    "at or below it, and ESTA files, are read as they are."
)


@dataclass(frozen=True, kw_only=True)
class RunOptions(ReplaySpec):
    """How `decoy replay` and `decoy evaluate` run a round: the replay's spec (`ReplaySpec`:
    the mover, shooting, the bomb, the seed, who decides deaths, missing fields and implausible
    data), each field an option, and the damage models and the geometry of sight."""

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
    rate: Annotated[float | None, typer.Option("--rate", help=RATE_HELP, min=0.1, max=128)] = None
    seed: Annotated[
        int,
        typer.Option(
            "--seed",
            help="Seed of the simulator's random numbers (and of the rounds evaluate --sample "
            "draws).",
        ),
    ] = 0


@dataclass(frozen=True)
class SampleOptions:
    """How `decoy train` and `decoy models` read and split the damage samples: the same
    options give the same train, validation and test parts in every command."""

    mode: Annotated[
        SampleMode,
        typer.Option(
            "--mode",
            help="How rounds become samples: auto (frames of both teams -> frames, else "
            "events), frames (the paper's, per frame every enemy pair) or events (events-only "
            "proxy for files without frames).",
        ),
    ] = DEFAULT_MODE
    window: Annotated[
        float,
        typer.Option(
            "--window",
            help="Events mode: seconds within which an event row places a player (negatives).",
        ),
    ] = DEFAULT_WINDOW_S
    split: Annotated[
        SplitUnit, typer.Option("--split", help="Split unit (never single samples).")
    ] = DEFAULT_SPLIT
    seed: Annotated[
        int,
        typer.Option(
            "--seed",
            help="Seed of the split, the 1:1 balancing, and (training) weights and shuffling.",
        ),
    ] = DEFAULT_SEED
    val_fraction: Annotated[
        float,
        typer.Option(
            "--val-fraction",
            help="Share of the split units for validation (early stopping, DIP threshold).",
        ),
    ] = DEFAULT_VAL_FRACTION
    test_fraction: Annotated[
        float,
        typer.Option(
            "--test-fraction", help="Share of the split units held out for the test metrics."
        ),
    ] = DEFAULT_TEST_FRACTION

    def choice(self, data: Sequence[Path]) -> SampleChoice:
        """The library's choice of samples: these options over `data`."""
        return SampleChoice(
            data=data,
            mode=self.mode,
            window_s=self.window,
            split_by=self.split,
            seed=self.seed,
            val_fraction=self.val_fraction,
            test_fraction=self.test_fraction,
        )
