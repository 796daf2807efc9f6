"""The damage models the simulator loads (`--models`), with torch imported lazily: what run time
needs and nothing of the tooling that makes the models (decoy_cli/modeling/).

* choice.py: the `--models` choice (`ModelName`, `ModelFolder`, `parse_models`);
* features.py: the model inputs, built in one place for training and simulation (numpy only);
* networks.py: DipNet and DogNet (torch), without their losses;
* model_folder.py: the saved-model format (a folder of dip/dog .pt + .json);
* model_maps.py: the maps a model knows, the DIP of a choice, and the warnings;
* calibration.py: DIP's calibration as the fight applies it (`dip_calibration.json`);
* combat.py: `DipDecision` (who hits) and `LearnedDamage`, the simulator's `DamageModel` over a
  DIP and a DOG;
* rules.py: CS:GO's damage rules (damage per bullet by weapon, hit group, range and armour);
  hit_groups.py, bullet_counts.py, rules_damage.py: `RulesDamage`, the DIP with damage by the
  rules and the learned parts of a folder's `rules.json`.

Importing this package does not import torch; `load_damage_model` does, when it loads a model.
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

from decoy_cli.damage.choice import ModelChoice, ModelFolder, ModelName, parse_models
from decoy_cli.errors import ModelError
from decoy_cli.package_data import packaged_dir

if TYPE_CHECKING:
    from decoy_cli.sim.combat import DamageModel

SHIPPED_MODELS = packaged_dir("models")
"""The project's own trained DIP and DOG (top-level `models/`, installed as decoy_cli.models)."""

DEFAULT_MODELS = ModelName.RULES
"""What `--models` is unless told: the shipped DIP (on features that name no place, so one for
every map) with damage by the game's rules, the combination that measures best on the real
damage events (README, "Damage models")."""

SHIPPED_CHOICES = (ModelName.SHIPPED, ModelName.RULES)
"""The `--models` choices that name the shipped folder (its DOG, or its rules)."""

CHOICES_HELP = (
    '"shipped" (the DIP and DOG shipped with decoy), "rules" (the shipped DIP with damage by '
    'the game\'s rules), "paper" (the paper\'s, once imported), "none" (no shooting) or a '
    "model folder; the shipped DIP takes features that name no place (distance, height, "
    "bearings, HP), one for every map"
)


def shipped_models_installed() -> bool:
    """True when the package holds its trained DIP and DOG."""
    return (SHIPPED_MODELS / "dip.json").is_file() and (SHIPPED_MODELS / "dog.json").is_file()


PAPER_FOLDER = Path("decoy-out") / "models" / "paper"
"""Where `decoy models import-decoy` and `download-decoy` write the paper's models unless told:
`--models paper` uses a folder `paper` when there is one, else this one."""


def resolve_models(choice: ModelChoice) -> Path:
    """The model folder a `--models` choice names (not "none"): the shipped one for "shipped"
    and "rules", a folder for "paper" (`PAPER_FOLDER`) or a path. A missing folder is one
    ModelError line."""
    if choice in SHIPPED_CHOICES:
        if not shipped_models_installed():
            raise ModelError(
                f"no shipped damage models in {SHIPPED_MODELS}: pass a model folder "
                "(e.g. from `decoy models import-decoy`) or none"
            )
        return SHIPPED_MODELS
    folder = Path(str(choice)).expanduser()
    if choice == ModelName.PAPER and not folder.is_dir():
        folder = PAPER_FOLDER
        if not folder.is_dir():
            raise ModelError(
                "paper: no folder paper or decoy-out/models/paper: import the paper's models "
                "first (decoy models download-decoy, or import-decoy CHECKPOINTS)"
            )
    if not folder.is_dir():
        raise ModelError(f"{choice}: no such model folder (expected {CHOICES_HELP})")
    return folder


def damages_by_rules(choice: ModelChoice, folder: Path) -> bool:
    """True when the choice's damage comes from the game's rules (`rules.json`), False when
    from the folder's DOG: "rules", or a folder with a rules.json and no DOG."""
    from decoy_cli.damage.rules_damage import RULES_FILE

    return choice == ModelName.RULES or (
        # exists, not is_file: a rules.json that is no regular file is refused when loaded
        (folder / RULES_FILE).exists() and not (folder / "dog.json").exists()
    )


def model_roles(choice: ModelChoice) -> dict[str, str]:
    """Which model decides who hits and which how much, in words, for a `--models` choice (a
    folder that cannot be read names itself only); the same on every map."""
    from decoy_cli.damage.model_maps import dip_of

    if choice == ModelName.NONE:
        return {"hits": "none (no shooting)", "damage": "none (no shooting)"}
    try:
        folder = resolve_models(choice)
    except ModelError:
        return {"hits": f"the DIP of {choice}", "damage": f"the models of {choice}"}
    name = "the shipped models" if folder == SHIPPED_MODELS else str(folder)
    if damages_by_rules(choice, folder):
        damage = f"the game's damage rules with the learned parts of {name} (rules.json)"
    else:
        damage = f"the DOG of {name}"
    return {"hits": dip_of(choice).name, "damage": damage}


def load_damage_model(choice: ModelChoice | str) -> DamageModel | None:
    """The damage model a user chose: "shipped", "rules", "none" (None: no shooting), "paper"
    or the path of a model folder holding a DIP and a DOG (e.g. written by `decoy models
    import-decoy`) or a DIP and `rules.json` (`decoy models fit-rules`: damage by the game's
    rules).

    The choice may be given as its text (`parse_models`). A missing or incompatible folder is
    one ModelError line.
    """
    choice = parse_models(choice)
    if choice == ModelName.NONE:
        return None
    folder = resolve_models(choice)
    from decoy_cli.damage.combat import LearnedDamage
    from decoy_cli.damage.model_folder import load_dip, load_dog
    from decoy_cli.damage.rules_damage import RulesDamage, RulesFile

    if damages_by_rules(choice, folder):
        return RulesDamage(load_dip(folder), RulesFile.load(folder))
    return LearnedDamage(load_dip(folder), load_dog(folder))


__all__ = [
    "CHOICES_HELP",
    "DEFAULT_MODELS",
    "PAPER_FOLDER",
    "SHIPPED_CHOICES",
    "SHIPPED_MODELS",
    "ModelChoice",
    "ModelFolder",
    "ModelName",
    "damages_by_rules",
    "load_damage_model",
    "model_roles",
    "parse_models",
    "resolve_models",
    "shipped_models_installed",
]
