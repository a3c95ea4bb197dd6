"""The packaged default recipe (``retarget train`` with no recipe file uses it)."""

from __future__ import annotations

from importlib.resources import files
from pathlib import Path


def default_recipe_path() -> Path:
    return Path(str(files("retarget.recipes").joinpath("default.yaml")))
