"""Where the data shipped with decoy lives: the map assets and the damage models.

In the repository they are the top-level folders `assets/` and `models/` beside `decoy_cli/`;
packaging installs them as the packages `decoy_cli.assets` and `decoy_cli.models` (setup.py).
"""

from __future__ import annotations

from importlib import resources
from pathlib import Path
from typing import Literal

PackagedFolder = Literal["assets", "models"]

_ROOT = Path(__file__).resolve().parents[1]


def packaged_dir(name: PackagedFolder) -> Path:
    """The folder of shipped data `name` ("assets" or "models").

    Code imported from a source checkout (an editable install, or run from the repository) uses
    the checkout's own top-level folder, so its data always matches its code; an installed wheel
    uses its package `decoy_cli.<name>`.
    """
    if (_ROOT / "pyproject.toml").is_file() and (_ROOT / name / "__init__.py").is_file():
        return _ROOT / name
    return Path(str(resources.files(f"decoy_cli.{name}")))
