"""Command-line changes to a raw recipe dict, applied *before* validation.

``--set a.b=c`` works on any path (values parsed as YAML, so ``3``, ``true``, ``[a, b]`` have
their natural types); ``--character dino --sensors hmd`` are shorthands for whole components.
Because overrides touch the raw dict, the same validation and error messages apply either way,
and each changed path remembers the flag that changed it so errors can point at the flag.
"""

from __future__ import annotations

import copy
from collections.abc import Iterable
from typing import Any

import yaml

from retarget.errors import RecipeError
from retarget.recipe.source import RecipeSource

SHORTHANDS: dict[str, str] = {
    "character": "character",
    "scene": "scene",
    "sensors": "sensors",
    "observers": "observers",
    "algorithm": "algorithm",
    "motions": "motions.path",
    "include": "motions.include",
    "exclude": "motions.exclude",
    "seed": "seed",
    "name": "name",
}
"""CLI flag -> recipe path it sets. ``sensors``/``observers``/``include``/``exclude`` take
comma-separated lists."""


def parse_assignment(text: str) -> tuple[str, Any]:
    """``"a.b=3"`` -> ``("a.b", 3)``; the value is parsed as YAML."""
    if "=" not in text:
        raise RecipeError(
            f"--set expects PATH=VALUE, got '{text}'", hint="for example --set seed=3"
        )
    path, raw = text.split("=", 1)
    path = path.strip()
    if not path or any(not part for part in path.split(".")):
        raise RecipeError(f"--set has an empty path segment in '{text}'")
    try:
        value = yaml.safe_load(raw) if raw.strip() else ""
    except yaml.YAMLError as exc:
        raise RecipeError(f"--set {path}: value is not valid YAML: {exc}") from None
    return path, value


def set_path(data: dict[str, Any], path: str, value: Any, flag: str) -> None:
    """Set ``data[a][b]... = value``, creating mappings on the way; lists take indices."""
    parts = path.split(".")
    node: Any = data
    for i, part in enumerate(parts[:-1]):
        here = ".".join(parts[: i + 1])
        if isinstance(node, list):
            node = _list_item(node, part, here, flag)
            continue
        child = node.get(part)
        if child is None:
            child = node[part] = {}
        elif isinstance(child, str) and i == 0:
            child = node[part] = {"type": child}  # 'character: dino' + --set character.x=1
        elif not isinstance(child, dict | list):
            raise RecipeError(
                f"cannot set '{path}': '{here}' is a {type(child).__name__}, not a mapping",
                file=f"command line ({flag})",
            )
        node = child
    last = parts[-1]
    if isinstance(node, list):
        index = _index(node, last, path, flag)
        node[index] = value
    else:
        node[last] = value


def _index(node: list, part: str, here: str, flag: str) -> int:
    try:
        index = int(part)
        node[index]
    except (ValueError, IndexError):
        raise RecipeError(
            f"'{here}': '{part}' is not an index of a list of {len(node)}",
            file=f"command line ({flag})",
        ) from None
    return index


def _list_item(node: list, part: str, here: str, flag: str) -> Any:
    item = node[_index(node, part, here, flag)]
    if isinstance(item, str):
        item = node[int(part)] = {"type": item}
    return item


def apply_overrides(
    source: RecipeSource,
    *,
    shorthands: dict[str, str | None] | None = None,
    assignments: Iterable[str] = (),
) -> RecipeSource:
    """A new source with shorthand flags, then ``--set`` assignments, applied in that order."""
    data = copy.deepcopy(source.data)
    changed = dict(source.overrides)
    for flag, value in (shorthands or {}).items():
        if value is None:
            continue
        path = SHORTHANDS[flag]
        parsed: Any = value
        if flag in {"sensors", "observers", "include", "exclude"}:
            parsed = [part.strip() for part in str(value).split(",") if part.strip()]
        elif flag == "seed":
            parsed = _int(value, flag)
        set_path(data, path, parsed, f"--{flag} {value}")
        changed[path] = f"--{flag} {value}"
    for text in assignments:
        path, value = parse_assignment(text)
        set_path(data, path, value, f"--set {text}")
        changed[path] = f"--set {text}"
    return RecipeSource(data=data, path=source.path, lines=source.lines, overrides=changed)


def _int(value: str, flag: str) -> int:
    try:
        return int(value)
    except ValueError:
        raise RecipeError(f"--{flag} expects an integer, got '{value}'") from None
