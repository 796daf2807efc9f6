"""Which maps a model was trained on, and the warnings when it is used on others.

A model folder says it in its metadata: `dip.json` and `dog.json` under "metadata" -> "maps"
(`decoy train` writes the maps of its training samples, `decoy models import-decoy` the paper's
eight), `rules.json` under "provenance" -> "maps" (`decoy models fit-rules`). A model knows no
map it was not trained on: the networks take a map one-hot and positions in that map's frame,
so on another map what they say is not to be trusted; the rules' learned parts (where bullets
land, how many per step) are not tied to a map's geometry, but were still measured on these.
"""

from __future__ import annotations

import json
from collections.abc import Iterable
from dataclasses import dataclass
from pathlib import Path

from decoy_cli.damage.choice import ModelChoice, ModelName
from decoy_cli.damage.rules_model import RULES_FILE

ANY_MAP = "any_map"
"""The subfolder of the shipped models holding the map-independent DIP (module doc)."""


@dataclass(frozen=True)
class MapDip:
    """The DIP that decides hits on one map for a `--models` choice: the folder whose dip.json
    it is, its name in words, and whether it stands in for the choice's own DIP (`fallback`:
    the map is not one that DIP was trained on)."""

    folder: Path
    name: str
    fallback: bool


def any_map_folder() -> Path | None:
    """The shipped map-independent DIP's folder, None when the package lacks it."""
    from decoy_cli.damage import SHIPPED_MODELS

    folder = SHIPPED_MODELS / ANY_MAP
    return folder if (folder / "dip.json").is_file() else None


def stand_in_of(choice: ModelChoice) -> tuple[Path, frozenset[str]] | None:
    """(the folder of the DIP that stands in off the choice's own DIP's maps, those maps) for
    the shipped choices when the map-independent DIP (`ANY_MAP`) is installed; None otherwise
    (a user's folder keeps its DIP everywhere). The one rule `dip_for_map` and the loaded
    models (`load_damage_model`) follow."""
    from decoy_cli.damage import SHIPPED_CHOICES, resolve_models

    fallback = any_map_folder()
    if choice not in SHIPPED_CHOICES or fallback is None:
        return None
    return fallback, frozenset(trained_maps(resolve_models(choice), "dip") or [])


def dip_for_map(choice: ModelChoice, map_name: str) -> MapDip:
    """The DIP that decides hits on `map_name` for a `--models` choice (not "none"): the
    choice's own, or off its maps the stand-in (`stand_in_of`)."""
    from decoy_cli.damage import SHIPPED_MODELS, resolve_models

    folder = resolve_models(choice)
    stand_in = stand_in_of(choice)
    if stand_in is not None and map_name not in stand_in[1]:
        return MapDip(
            stand_in[0], f"the map-independent DIP of the shipped models ({ANY_MAP})", True
        )
    name = "the shipped models" if folder == SHIPPED_MODELS else str(folder)
    return MapDip(folder, f"the DIP of {name}", False)


def part_file(folder: Path, part: str) -> Path:
    """The file of a model folder's `part` ("dip", "dog" or "rules")."""
    return folder / (RULES_FILE if part == "rules" else f"{part}.json")


def trained_maps(folder: Path, part: str) -> list[str] | None:
    """The maps the folder's `part` ("dip", "dog" or "rules") was trained on; None when its
    file does not say (or cannot be read: loading it reports that)."""
    path = part_file(folder, part)
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
        maps = data["provenance" if part == "rules" else "metadata"]["maps"]
    except (OSError, ValueError, KeyError, TypeError):
        return None
    if not isinstance(maps, list) or not all(isinstance(m, str) for m in maps):
        return None
    return sorted(maps)


def map_warnings(choice: ModelChoice, maps: Iterable[str]) -> list[str]:
    """One line per model part of the `--models` choice that was not trained on every one of
    `maps` where it is used, naming the maps it was trained on (or saying it does not say),
    and where the map-independent DIP stands in for the choice's own (`dip_for_map`); none for
    "none"."""
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
    lines = _fallback_lines(choice, used)
    for part, what in parts.items():
        if not part_file(folder, part).is_file():
            continue
        # the maps where the part is used: the DIP's are not those where another stands in
        where = [m for m in used if part != "dip" or not dip_for_map(choice, m).fallback]
        known = trained_maps(folder, part)
        if not where:
            continue
        if known is None:
            lines.append(
                f"the {what} of --models {choice} does not say which maps it was trained on: "
                f"on {', '.join(where)} it may not be trusted"
            )
            continue
        other = [m for m in where if m not in known]
        if other:
            lines.append(
                f"the {what} of --models {choice} was trained on {', '.join(known)} only, not "
                f"on {', '.join(other)}: what it says there is not to be trusted"
            )
    return lines


def _fallback_lines(choice: ModelChoice, maps: list[str]) -> list[str]:
    """The lines of the maps where the map-independent DIP stands in for the choice's own
    (`dip_for_map`): which DIP decides hits there and the maps each was trained on, and the
    maps it never saw."""
    fallen = [m for m in maps if dip_for_map(choice, m).fallback]
    if not fallen:
        return []
    from decoy_cli.damage import resolve_models

    folder = resolve_models(choice)
    stand_in = dip_for_map(choice, fallen[0])
    own = ", ".join(trained_maps(folder, "dip") or []) or "maps it does not name"
    known = trained_maps(stand_in.folder, "dip")
    lines = [
        f"hits on {', '.join(fallen)} are decided by {stand_in.name}, not the DIP of --models "
        f"{choice} (trained on {own} only): it was trained on "
        f"{', '.join(known) if known else 'maps it does not name'} with features that name no "
        "place (distance, height difference, bearings, HP)"
    ]
    unseen = [m for m in fallen if known is not None and m not in known]
    if unseen:
        lines.append(
            f"{stand_in.name} never saw {', '.join(unseen)}: its hits there were not measured"
        )
    return lines
