"""The `--models` choice as a type: one of the named choices (`ModelName`) or a model folder
(`ModelFolder`), parsed once from the command line's text (`parse_models`)."""

from __future__ import annotations

from dataclasses import dataclass
from enum import StrEnum
from pathlib import Path


class ModelName(StrEnum):
    """The named `--models` choices."""

    RULES = "rules"
    """The shipped DIP with damage by the game's rules (`rules.json`)."""
    SHIPPED = "shipped"
    """The DIP and DOG shipped with decoy."""
    PAPER = "paper"
    """The paper's models, once imported (a folder `paper`, else `PAPER_FOLDER`)."""
    NONE = "none"
    """No damage model: no shooting."""


@dataclass(frozen=True)
class ModelFolder:
    """A model folder named on the command line, kept as the text given (it names the choice in
    outputs and reports as the user wrote it)."""

    text: str

    @property
    def path(self) -> Path:
        return Path(self.text).expanduser()

    def __str__(self) -> str:
        return self.text


ModelChoice = ModelName | ModelFolder
"""What `--models` chose."""

MODELS_METAVAR = "|".join(ModelName) + "|FOLDER"
"""The choices as `--help` lists them."""


def parse_models(text: str | ModelChoice) -> ModelChoice:
    """The choice `text` names: a `ModelName` when it is one, else a model folder (a choice
    passed in already parsed is returned as it is)."""
    if isinstance(text, ModelFolder):
        return text
    try:
        return ModelName(text)
    except ValueError:
        return ModelFolder(text)
