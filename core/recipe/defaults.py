"""The packaged recipes that ``retarget <verb>`` uses when no recipe file is given.

``default.yaml`` carries Jesse's column of the paper's Table 2 (a human-like body). Characters
whose bodies differ from a human's get their own column: ``--character dino`` without a recipe
file starts from ``dino.yaml`` (likewise ``oppy.yaml``), so the main command trains each body
with the reward weights the paper gives it. A recipe file given by the user is laid over the
packaged recipe for its character unless it says otherwise (:mod:`retarget.recipe.extends`).

Named packaged recipes are used by name instead of a file: ``retarget train paper`` (the
paper's torques and Table 3) or ``retarget train teacher --character dino`` (a full-body
imitator); a character's own variant ``CHARACTER_NAME.yaml`` is preferred when it exists.
"""

from __future__ import annotations

from importlib.resources import files
from pathlib import Path


def packaged_recipe(name: str) -> Path | None:
    """The packaged recipe ``NAME.yaml``, or None."""
    path = Path(str(files("retarget.recipes").joinpath(f"{name}.yaml")))
    return path if path.is_file() else None


def default_recipe_path(character: str | None = None) -> Path:
    """The character's packaged recipe if it has one, else ``default.yaml``."""
    if character:
        own = packaged_recipe(character)
        if own is not None:
            return own
    path = packaged_recipe("default")
    assert path is not None, "retarget.recipes/default.yaml is missing from the installation"
    return path


def named_recipe(name: str, character: str | None = None) -> Path | None:
    """The packaged recipe a bare name (no suffix, not a file) stands for, or None:
    ``CHARACTER_NAME.yaml`` if it exists, else ``NAME.yaml``."""
    if not name.isidentifier():
        return None
    if character:
        own = packaged_recipe(f"{character}_{name}")
        if own is not None:
            return own
    return packaged_recipe(name)


def is_packaged(path: str | Path) -> bool:
    """Whether ``path`` is one of the packaged recipes (they stand alone)."""
    folder = Path(str(files("retarget.recipes"))).resolve()
    return Path(path).resolve().parent == folder


def packaged_names() -> list[str]:
    """Names of the packaged recipes (for error messages)."""
    folder = Path(str(files("retarget.recipes")))
    return sorted(p.stem for p in folder.glob("*.yaml"))
