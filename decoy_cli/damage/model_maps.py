"""Which maps a model was trained on, and the warnings when it is used on others.

A model folder says it in its metadata: `dip.json` and `dog.json` under "metadata" -> "maps"
(`decoy train` writes the maps of its training samples, `decoy models import-decoy` the paper's
eight), `rules.json` under "provenance" -> "maps" (`decoy models fit-rules`). A model knows no
map it was not trained on: a network on the paper's normalised features takes a map one-hot and
positions in that map's frame, so on another map what it says is not to be trusted; one on
relative features (the shipped DIP) and the rules' learned parts (where bullets land, how many
per step) name no place, but were still measured on these maps only.
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass
from pathlib import Path

from decoy_cli.damage.choice import ModelChoice, ModelName
from decoy_cli.damage.rules_damage import RULES_FILE
from decoy_cli.errors import DecoyError
from decoy_cli.reading import load_json


@dataclass(frozen=True)
class ChosenDip:
    """The DIP that decides hits for a `--models` choice: the folder whose dip.json it is, and
    its name in words."""

    folder: Path
    name: str


def dip_of(choice: ModelChoice) -> ChosenDip:
    """The DIP that decides hits for a `--models` choice (not "none"), on every map."""
    from decoy_cli.damage import SHIPPED_MODELS, resolve_models

    folder = resolve_models(choice)
    name = "the shipped models" if folder == SHIPPED_MODELS else str(folder)
    return ChosenDip(folder, f"the DIP of {name}")


def part_file(folder: Path, part: str) -> Path:
    """The file of a model folder's `part` ("dip", "dog" or "rules")."""
    return folder / (RULES_FILE if part == "rules" else f"{part}.json")


def trained_maps(folder: Path, part: str) -> list[str] | None:
    """The maps the folder's `part` ("dip", "dog" or "rules") was trained on; None when its
    file does not say (or cannot be read: loading it reports that)."""
    path = part_file(folder, part)
    try:
        data = load_json(path)
    except DecoyError:
        return None
    key = "provenance" if part == "rules" else "metadata"
    section = data.get(key) if isinstance(data, dict) else None
    maps = section.get("maps") if isinstance(section, dict) else None
    if not isinstance(maps, list):
        return None
    names = [m for m in maps if isinstance(m, str)]
    return sorted(names) if len(names) == len(maps) else None


def map_warnings(choice: ModelChoice, maps: Iterable[str]) -> list[str]:
    """One line per model part of the `--models` choice that was not trained on every one of
    `maps` where it is used, naming the maps it was trained on (or saying it does not say);
    none for "none"."""
    from decoy_cli.damage import damages_by_rules, resolve_models

    if choice == ModelName.NONE:
        return []
    folder = resolve_models(choice)
    used = sorted(set(maps))
    parts = {"dip": "DIP (who hits)"}
    if damages_by_rules(choice, folder):
        parts["rules"] = "damage rules' learned parts (rules.json)"
    else:
        parts["dog"] = "DOG (how much damage)"
    lines = []
    for part, what in parts.items():
        if not part_file(folder, part).is_file():
            continue
        known = trained_maps(folder, part)
        if known is None:
            lines.append(
                f"the {what} of --models {choice} does not say which maps it was trained on: "
                f"on {', '.join(used)} it may not be trusted"
            )
            continue
        other = [m for m in used if m not in known]
        if other:
            lines.append(
                f"the {what} of --models {choice} was trained on {', '.join(known)} only, not "
                f"on {', '.join(other)}: what it says there is not to be trusted"
            )
    return lines
