"""Reading recipe files (YAML or TOML) into a raw dict, keeping where each field was written.

Line numbers let every later error point at ``recipe.yaml:12``; parse errors carry the
parser's own position.
"""

from __future__ import annotations

import tomllib
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import yaml

from retarget.errors import RecipeError


@dataclass
class RecipeSource:
    """A raw recipe dict plus its origin (file path, dotted path -> line, CLI overrides)."""

    data: dict[str, Any]
    path: str
    lines: dict[str, int] = field(default_factory=dict)
    overrides: dict[str, str] = field(default_factory=dict)  # dotted path -> the CLI flag

    def locate(self, dotted: str) -> tuple[str, int | None]:
        """Where ``dotted`` came from: the CLI flag that set it, or the file and line."""
        parts = dotted.split(".")
        for i in range(len(parts), 0, -1):
            prefix = ".".join(parts[:i])
            if prefix in self.overrides:
                return f"command line ({self.overrides[prefix]})", None
        for i in range(len(parts), 0, -1):
            prefix = ".".join(parts[:i])
            if prefix in self.lines:
                return self.path, self.lines[prefix]
        return self.path, None


MAX_VALUES = 100_000
"""Most values a recipe may expand to (YAML aliases can make a few lines expand to billions)."""
MAX_DEPTH = 64
"""Deepest nesting a recipe may have."""


class _TooBig(Exception):
    pass


def _yaml_lines(
    node: yaml.Node,
    prefix: str,
    out: dict[str, int],
    depth: int = 0,
    budget: list[int] | None = None,
) -> None:
    """Dotted path -> line of every value, counting them: a recipe that nests deeper than
    :data:`MAX_DEPTH` or expands past :data:`MAX_VALUES` values is refused."""
    budget = [MAX_VALUES] if budget is None else budget
    if depth > MAX_DEPTH:
        raise _TooBig(f"nests deeper than {MAX_DEPTH} levels")
    budget[0] -= 1
    if budget[0] < 0:
        raise _TooBig(f"expands to more than {MAX_VALUES} values (YAML aliases?)")
    if isinstance(node, yaml.MappingNode):
        for key_node, value_node in node.value:
            key = str(key_node.value)
            dotted = f"{prefix}.{key}" if prefix else key
            out[dotted] = key_node.start_mark.line + 1
            _yaml_lines(value_node, dotted, out, depth + 1, budget)
    elif isinstance(node, yaml.SequenceNode):
        for i, item in enumerate(node.value):
            dotted = f"{prefix}.{i}" if prefix else str(i)
            out[dotted] = item.start_mark.line + 1
            _yaml_lines(item, dotted, out, depth + 1, budget)


class _UniqueKeyLoader(yaml.SafeLoader):
    """``yaml.SafeLoader`` that refuses a key given twice in one mapping (YAML would keep the
    last one silently: a recipe that says one thing and does another)."""

    def construct_mapping(self, node: yaml.Node, deep: bool = False):  # type: ignore[override]
        seen: dict[object, int] = {}
        for key_node, _ in node.value:  # type: ignore[union-attr]
            key = self.construct_object(key_node, deep=deep)
            if isinstance(key, (str, int, float, bool)) and key in seen:
                raise yaml.constructor.ConstructorError(
                    None, None,
                    f"duplicate key '{key}' (first on line {seen[key]})",
                    key_node.start_mark,
                )
            if isinstance(key, (str, int, float, bool)):
                seen[key] = key_node.start_mark.line + 1
        return super().construct_mapping(node, deep=deep)  # type: ignore[arg-type]


LOCK_SECTION = "_lock"


def parse_text(text: str, path: str, suffix: str) -> RecipeSource:
    """Parse recipe text; ``suffix`` picks TOML for ``.toml``, YAML otherwise."""
    lines: dict[str, int] = {}
    if suffix == ".toml":
        try:
            data = tomllib.loads(text)
        except tomllib.TOMLDecodeError as exc:
            raise RecipeError(f"invalid TOML: {exc}", file=path) from None
    else:
        try:
            node = yaml.compose(text, Loader=yaml.SafeLoader)
            if node is not None:
                _yaml_lines(node, "", lines)  # bounded walk before anything is built
            loader = _UniqueKeyLoader(text)  # a SafeLoader: plain data only
            try:
                data = loader.get_single_data()
            finally:
                loader.dispose()
        except _TooBig as exc:
            raise RecipeError(f"refused: the recipe {exc}", file=path) from None
        except RecursionError:
            raise RecipeError(f"refused: the recipe nests deeper than {MAX_DEPTH} levels",
                              file=path) from None
        except yaml.MarkedYAMLError as exc:
            mark = exc.problem_mark or exc.context_mark
            line = mark.line + 1 if mark is not None else None
            problem = exc.problem or exc.context or "syntax error"
            raise RecipeError(f"invalid YAML: {problem}", file=path, line=line) from None
        except yaml.YAMLError as exc:
            raise RecipeError(f"invalid YAML: {exc}", file=path) from None
    if data is None:
        raise RecipeError("the recipe is empty", file=path)
    if not isinstance(data, dict):
        raise RecipeError(
            f"a recipe must be a mapping of fields, got {type(data).__name__}", file=path
        )
    # A run's recipe.lock.yaml is a recipe plus its provenance: training from it reproduces
    # the run, so the provenance section is read past rather than refused.
    data.pop(LOCK_SECTION, None)
    return RecipeSource(data=data, path=path, lines=lines)


def read_recipe_file(path: str | Path) -> RecipeSource:
    """Read a ``.yaml``/``.yml``/``.toml`` recipe; a missing or unreadable file is a RecipeError."""
    p = Path(path)
    if not p.exists():
        from retarget.recipe.defaults import packaged_names

        raise RecipeError(
            "recipe file not found", file=str(p),
            hint=f"packaged recipes by name: {', '.join(packaged_names())}",
        )
    if p.is_dir():
        raise RecipeError("expected a recipe file, got a directory", file=str(p))
    if p.suffix.lower() not in {".yaml", ".yml", ".toml"}:
        raise RecipeError(
            f"unknown recipe format '{p.suffix}'", file=str(p), hint="use .yaml, .yml or .toml"
        )
    try:
        text = p.read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError) as exc:
        raise RecipeError(f"cannot read: {exc}", file=str(p)) from None
    return parse_text(text, str(p), p.suffix.lower())
