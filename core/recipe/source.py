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


def _yaml_lines(node: yaml.Node, prefix: str, out: dict[str, int]) -> None:
    if isinstance(node, yaml.MappingNode):
        for key_node, value_node in node.value:
            key = str(key_node.value)
            dotted = f"{prefix}.{key}" if prefix else key
            out[dotted] = key_node.start_mark.line + 1
            _yaml_lines(value_node, dotted, out)
    elif isinstance(node, yaml.SequenceNode):
        for i, item in enumerate(node.value):
            dotted = f"{prefix}.{i}" if prefix else str(i)
            out[dotted] = item.start_mark.line + 1
            _yaml_lines(item, dotted, out)


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
            data = yaml.safe_load(text)
            node = yaml.compose(text)
        except yaml.MarkedYAMLError as exc:
            mark = exc.problem_mark or exc.context_mark
            line = mark.line + 1 if mark is not None else None
            problem = exc.problem or exc.context or "syntax error"
            raise RecipeError(f"invalid YAML: {problem}", file=path, line=line) from None
        except yaml.YAMLError as exc:
            raise RecipeError(f"invalid YAML: {exc}", file=path) from None
        if node is not None:
            _yaml_lines(node, "", lines)
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
