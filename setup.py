"""Packaging beyond pyproject.toml: the top-level `assets/` and `models/` folders ship inside the
package as `decoy_cli.assets` and `decoy_cli.models` (found by `decoy_cli.package_data`)."""

from setuptools import find_namespace_packages, setup

SHIPPED_DATA = {"decoy_cli.assets": "assets", "decoy_cli.models": "models"}

setup(
    packages=[
        *find_namespace_packages(include=["decoy_cli", "decoy_cli.*"], exclude=["*.__pycache__"]),
        *SHIPPED_DATA,
    ],
    package_dir=SHIPPED_DATA,
    package_data={
        "decoy_cli.assets": ["*/*.csv", "*/*.json", "*/*.npz", "*/*.md"],
        "decoy_cli.models": ["*.json", "*.pt", "*.md"],
    },
)
