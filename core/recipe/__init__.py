"""Declarative recipes: parse, override, validate, resolve, lock, schema."""

from __future__ import annotations

from retarget.recipe.defaults import default_recipe_path
from retarget.recipe.lock import lock_data, write_lock
from retarget.recipe.model import ComponentRef, Recipe
from retarget.recipe.overrides import apply_overrides
from retarget.recipe.resolve import Component, ResolvedRecipe, load, resolve
from retarget.recipe.schema import recipe_schema
from retarget.recipe.source import RecipeSource, parse_text, read_recipe_file

__all__ = [
    "Component",
    "ComponentRef",
    "Recipe",
    "RecipeSource",
    "ResolvedRecipe",
    "apply_overrides",
    "default_recipe_path",
    "load",
    "lock_data",
    "parse_text",
    "read_recipe_file",
    "recipe_schema",
    "resolve",
    "write_lock",
]
