"""Phase 2 of recipe validation: plugin lookup, per-plugin ``Config``, cross-checks, instances.

Nothing expensive happens here (no MJCF compile, no data loading), so a bad recipe fails in
well under a second with the file, the dotted field path and the plugin named.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from pydantic import ValidationError

from retarget.errors import PluginError, RecipeError, RetargetError
from retarget.kinds import Character, Plugin, PluginConfig
from retarget.kinds.lookup import PluginLookup
from retarget.recipe.errors import from_validation
from retarget.recipe.model import SLOTS, ComponentRef, Recipe
from retarget.recipe.source import RecipeSource
from retarget.registry import Entry


@dataclass(frozen=True)
class Component:
    """One resolved component: where it sits in the recipe, its plugin entry and config."""

    path: str  # dotted recipe path, e.g. "rewards.action_diff"
    entry: Entry
    config: PluginConfig

    def instantiate(self) -> Plugin:
        try:
            return self.entry.cls(self.config)
        except RetargetError:  # already names the file, field or plugin
            raise
        except Exception as exc:
            raise PluginError(
                f"constructor raised {type(exc).__name__}: {exc}",
                field=self.path,
                plugin=f"{self.entry.name} ({self.entry.distribution})",
            ) from exc


@dataclass(frozen=True)
class ResolvedRecipe:
    """A validated recipe: every component's plugin class and typed config, not yet built."""

    recipe: Recipe
    source: RecipeSource
    components: dict[str, Component] = field(default_factory=dict)

    def component(self, path: str) -> Component:
        return self.components[path]

    def of_kind(self, kind: str) -> list[Component]:
        return [c for c in self.components.values() if c.entry.kind == kind]

    @property
    def character(self) -> Component:
        return self.components["character"]

    def to_dict(self, configs: Mapping[str, PluginConfig] | None = None) -> dict[str, Any]:
        """The recipe with every default filled in (what ``recipe show`` prints); ``configs``
        replaces the config of the components at those paths (``sensors.1``)."""
        data = self.recipe.model_dump(mode="json")
        for path, comp in self.components.items():
            config = (configs or {}).get(path, comp.config)
            filled = {"type": comp.entry.name, **config.model_dump(mode="json")}
            _assign(data, path, filled)
        return data


def _assign(data: dict[str, Any], path: str, value: Any) -> None:
    parts = path.split(".")
    node: Any = data
    for part in parts[:-1]:
        node = node[int(part)] if isinstance(node, list) else node[part]
    last = parts[-1]
    if isinstance(node, list):
        node[int(last)] = value
    else:
        node[last] = value


def validate_structure(source: RecipeSource) -> Recipe:
    try:
        return Recipe.model_validate(source.data)
    except ValidationError as exc:
        raise from_validation(exc, source, model=Recipe) from None


def _refs(recipe: Recipe) -> list[tuple[str, str, ComponentRef]]:
    """(dotted path, kind, ref) of every component in the recipe, in a stable order."""
    out: list[tuple[str, str, ComponentRef]] = []
    for slot, kind in SLOTS.items():
        value = getattr(recipe, slot)
        if value is None:
            continue
        if isinstance(value, list):
            out += [(f"{slot}.{i}", kind, ref) for i, ref in enumerate(value)]
        elif isinstance(value, dict):
            out += [(f"{slot}.{key}", kind, ref) for key, ref in value.items()]
        else:
            out.append((slot, kind, value))
    if recipe.motions.format is not None:
        out.append(("motions.format", "motion_format", recipe.motions.format))
    return out


def resolve(source: RecipeSource, registry: PluginLookup) -> ResolvedRecipe:
    """Validate ``source`` against the installed plugins; raises one RecipeError on failure."""
    recipe = validate_structure(source)
    components: dict[str, Component] = {}
    for path, kind, ref in _refs(recipe):
        try:
            entry = registry.get(kind, ref.type)
        except PluginError as exc:
            file, line = source.locate(f"{path}.type")
            raise RecipeError(
                exc.message, file=file, line=line, field=f"{path}.type", hint=exc.hint
            ) from None
        plugin_label = f"{entry.name} ({entry.distribution})"
        try:
            config = entry.cls.Config.model_validate(ref.params)
        except ValidationError as exc:
            raise from_validation(
                exc, source, prefix=path, plugin=plugin_label, model=entry.cls.Config
            ) from None
        components[path] = Component(path, entry, config)
    resolved = ResolvedRecipe(recipe=recipe, source=source, components=components)
    cross_check(resolved)
    return resolved


def cross_check(resolved: ResolvedRecipe) -> None:
    """What components ``require`` (``site:head``, ``body_group:feet``) the character provides.

    Runs on configs alone, before any model is compiled.
    """
    char_comp = resolved.character
    character = char_comp.instantiate()
    assert isinstance(character, Character)
    try:
        provided = {f"site:{s}" for s in character.site_roles()} | {
            f"body_group:{g}" for g in character.body_groups()
        }
    except Exception as exc:
        raise PluginError(
            f"could not list sites/groups: {type(exc).__name__}: {exc}",
            field="character",
            plugin=char_comp.entry.name,
        ) from exc
    for comp in resolved.components.values():
        needed = set(getattr(comp.entry.cls, "requires", ()))
        missing = sorted(needed - provided)
        if missing:
            file, line = resolved.source.locate(comp.path)
            raise RecipeError(
                f"needs {', '.join(missing)}, which character '{char_comp.entry.name}' "
                "does not provide",
                file=file,
                line=line,
                field=comp.path,
                plugin=comp.entry.name,
                hint=f"the character provides: {', '.join(sorted(provided)) or 'nothing'}",
            )


def load(
    path: str | Path | None,
    registry: PluginLookup,
    *,
    shorthands: dict[str, str | None] | None = None,
    assignments: list[str] | tuple[str, ...] = (),
) -> ResolvedRecipe:
    """Read (or take the packaged default), override, validate and resolve a recipe."""
    from retarget.recipe.defaults import default_recipe_path, is_packaged, named_recipe
    from retarget.recipe.extends import extended
    from retarget.recipe.overrides import apply_overrides
    from retarget.recipe.source import read_recipe_file

    character = (shorthands or {}).get("character")
    if path is None:
        path = default_recipe_path(character)
    elif not Path(path).exists() and not Path(path).suffix:
        path = named_recipe(str(path), character) or path
    source = read_recipe_file(path)
    if not is_packaged(path):  # a user's file starts from the packaged recipe for its body
        source = extended(source, character)
    source = apply_overrides(source, shorthands=shorthands, assignments=assignments)
    return resolve(source, registry)
