"""The recipe argument and its override flags, for every command that reads a recipe.

Core verbs and command plugins share these so that ``retarget train``, ``retarget bench`` and a
third party's command accept the same recipe file, shorthands and ``--set`` assignments. A
toolkit module (see :mod:`retarget.testing.toolkit`).
"""

from __future__ import annotations

import argparse
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from retarget.kinds.lookup import PluginLookup
    from retarget.recipe import ResolvedRecipe


def add_recipe_flags(parser: argparse.ArgumentParser) -> None:
    """The recipe argument and override flags shared by every verb that reads a recipe."""
    parser.add_argument("recipe", nargs="?", help="recipe file (.yaml/.toml); default: packaged")
    parser.add_argument("--character", help="character plugin name, e.g. dino")
    parser.add_argument("--sensors", help="comma-separated sensor plugin names, e.g. hmd")
    parser.add_argument("--observers", help="comma-separated observer plugin names")
    parser.add_argument("--scene", help="scene plugin name")
    parser.add_argument("--algorithm", help="algorithm plugin name")
    parser.add_argument("--motions", help="motion file, directory or archive (.tar.gz, .zip)")
    add_pick_flags(parser)
    parser.add_argument("--seed", help="random seed")
    add_set_flag(parser, "override any recipe field, e.g. --set rewards.action_diff.weight=0.2")


def add_pick_flags(parser: argparse.ArgumentParser) -> None:
    """``--include``/``--exclude``: comma-separated shell patterns on motion file names."""
    parser.add_argument(
        "--include", metavar="PATTERNS", help="only motion files matching these, e.g. '*_walk*'"
    )
    parser.add_argument(
        "--exclude", metavar="PATTERNS", help="leave these motion files out, e.g. '*_normal_*'"
    )


def patterns(text: str | None) -> list[str] | None:
    """``--include``/``--exclude`` as a list (None when the flag was not given)."""
    return None if text is None else [p.strip() for p in text.split(",") if p.strip()]


def add_set_flag(parser: argparse.ArgumentParser, help: str) -> None:
    """``--set PATH=VALUE`` (repeatable) into ``args.assignments``."""
    parser.add_argument(
        "--set", dest="assignments", action="append", default=[], metavar="PATH=VALUE", help=help
    )


def shorthands(args: argparse.Namespace) -> dict[str, str | None]:
    """The shorthand flags' values, keyed as :func:`retarget.recipe.load` expects them."""
    keys = ("character", "sensors", "observers", "scene", "algorithm", "motions", "include",
            "exclude", "seed")
    return {key: getattr(args, key, None) for key in keys}


def load_from_args(args: argparse.Namespace, registry: PluginLookup) -> ResolvedRecipe:
    """The recipe those flags describe, resolved against ``registry`` (the invocation's)."""
    from retarget.recipe import load

    return load(args.recipe, registry, shorthands=shorthands(args), assignments=args.assignments)
