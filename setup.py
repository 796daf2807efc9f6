"""Packaging beyond pyproject.toml: the top-level `assets/` and `models/` folders ship inside the
package as `decoy_cli.assets` and `decoy_cli.models` (found by `decoy_cli.package_data`)."""

from setuptools import find_namespace_packages, setup

SHIPPED_DATA = {"decoy_cli.assets": "assets", "decoy_cli.models": "models"}
DATA_FILES = ["*.csv", "*.json", "*.npz", "*.md", "*.pt"]

# Every folder below them (one per map in assets/) is a data package of its own.
shipped = [
    name
    for package, folder in SHIPPED_DATA.items()
    for name in (
        package,
        *(f"{package}.{sub}" for sub in find_namespace_packages(folder, exclude=["*__pycache__"])),
    )
]

setup(
    packages=[
        *find_namespace_packages(include=["decoy_cli", "decoy_cli.*"], exclude=["*__pycache__"]),
        *shipped,
    ],
    package_dir=SHIPPED_DATA,
    package_data={
        **{package: DATA_FILES for package in shipped},
        "decoy_cli.view": [
            "page.html",
            "page.css",
            *(f"{n}.js" for n in ("data", "draw", "controls", "tables")),
        ],
    },
)
