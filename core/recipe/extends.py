"""A recipe file starts from another recipe: by default the packaged one for its character.

A user's recipe usually changes a few things (a sensor, a reward weight, the scene); written
alone it would train without tracking rewards or an algorithm. So a file is laid over a base
recipe before it is validated: ``extends: dino`` (a packaged recipe by name), ``extends:
../base.yaml`` (a file, relative to this one), ``extends: null`` (stand-alone, as a run's
``recipe.lock.yaml`` is), and without the key the packaged default for its ``character``.

Laying over: mappings merge key by key (``sim``, ``env``, ``motions``, and the reward and
termination tables, where ``name: null`` removes an entry); a component keeps the base's
settings unless it names another ``type``; lists (``sensors``, ``observers``) replace.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

from retarget.errors import RecipeError
from retarget.recipe.source import RecipeSource, read_recipe_file

KEY = "extends"
COMPONENTS = {"character", "scene", "algorithm"}
TABLES = {"rewards", "terminations"}
MAX_CHAIN = 8
"""Deepest chain of ``extends`` followed (a loop is an error, not a hang)."""


def _component(value: Any) -> Any:
    return {"type": value} if isinstance(value, str) else value


def _lay_component(base: Any, over: Any) -> Any:
    base, over = _component(base), _component(over)
    if isinstance(base, dict) and isinstance(over, dict):
        if "type" in over and over.get("type") != base.get("type"):
            return over  # another plugin: the base's settings are not its settings
        return {**base, **over}
    return over


def lay_over(base: dict[str, Any], over: dict[str, Any]) -> dict[str, Any]:
    """``over`` laid over ``base`` (see the module docstring)."""
    out = dict(base)
    for key, value in over.items():
        if key in COMPONENTS and key in base:
            out[key] = _lay_component(base[key], value)
        elif key in TABLES and isinstance(value, dict) and isinstance(base.get(key), dict):
            table = dict(base[key])
            for name, entry in value.items():
                if entry is None:
                    table.pop(name, None)
                else:
                    table[name] = _lay_component(table[name], entry) if name in table else entry
            out[key] = table
        elif isinstance(value, dict) and isinstance(base.get(key), dict):
            out[key] = {**base[key], **value}
        else:
            out[key] = value
    return out


def _character(data: dict[str, Any], fallback: str | None) -> str | None:
    ref = data.get("character")
    if isinstance(ref, str):
        return ref
    if isinstance(ref, dict) and isinstance(ref.get("type"), str):
        return ref["type"]
    return fallback


def _base_path(source: RecipeSource, spec: Any, character: str | None) -> Path:
    from retarget.recipe.defaults import default_recipe_path, named_recipe, packaged_names

    if not isinstance(spec, str) or not spec:
        raise RecipeError(
            "extends names a packaged recipe or a recipe file, or is null",
            file=source.path, line=source.lines.get(KEY), field=KEY,
        )  # fmt: skip
    if spec == "default":
        return default_recipe_path(character)
    packaged = named_recipe(spec, None)
    if packaged is not None:
        return packaged
    path = Path(spec)
    if not path.is_absolute():
        path = Path(source.path).parent / path
    if not path.exists():
        raise RecipeError(
            f"extends '{spec}': no such packaged recipe or file",
            file=source.path, line=source.lines.get(KEY), field=KEY,
            hint=f"packaged recipes: {', '.join(packaged_names())}",
        )  # fmt: skip
    return path


def extended(source: RecipeSource, character: str | None = None) -> RecipeSource:
    """``source`` laid over its base recipe (chains followed up to :data:`MAX_CHAIN`)."""
    from retarget.recipe.defaults import default_recipe_path

    data, seen = dict(source.data), [str(Path(source.path).resolve())]
    has_key = KEY in data
    spec = data.pop(KEY, None)
    who = _character(data, character)
    current = source
    while has_key is False or spec is not None:
        base_path = default_recipe_path(who) if not has_key else _base_path(current, spec, who)
        resolved = str(base_path.resolve())
        if resolved in seen:
            raise RecipeError(f"extends loops back to {base_path}", file=source.path, field=KEY)
        if len(seen) > MAX_CHAIN:
            raise RecipeError(f"extends chains more than {MAX_CHAIN} recipes", file=source.path)
        seen.append(resolved)
        current = read_recipe_file(base_path)
        base = dict(current.data)
        has_key, spec = KEY in base, base.pop(KEY, None)
        if not has_key:
            has_key, spec = True, None  # a packaged recipe stands alone
        data = lay_over(base, data)
    data[KEY] = None  # what results is complete: reading it again adds nothing
    return RecipeSource(data=data, path=source.path, lines=source.lines,
                        overrides=source.overrides)  # fmt: skip
