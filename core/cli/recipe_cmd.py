"""``retarget recipe validate|show|schema``."""

from __future__ import annotations

import argparse
import json

from retarget.registry import Registry


def add_recipe_flags(parser: argparse.ArgumentParser) -> None:
    """The recipe argument and override flags shared by every verb that reads a recipe."""
    parser.add_argument("recipe", nargs="?", help="recipe file (.yaml/.toml); default: packaged")
    parser.add_argument("--character", help="character plugin name, e.g. dino")
    parser.add_argument("--sensors", help="comma-separated sensor plugin names, e.g. hmd")
    parser.add_argument("--observers", help="comma-separated observer plugin names")
    parser.add_argument("--scene", help="scene plugin name")
    parser.add_argument("--algorithm", help="algorithm plugin name")
    parser.add_argument("--motions", help="motion file or directory")
    parser.add_argument("--seed", help="random seed")
    add_set_flag(parser, "override any recipe field, e.g. --set rewards.action_diff.weight=0.2")


def add_set_flag(parser: argparse.ArgumentParser, help: str) -> None:
    """``--set PATH=VALUE`` (repeatable) into ``args.assignments``."""
    parser.add_argument(
        "--set", dest="assignments", action="append", default=[], metavar="PATH=VALUE", help=help
    )


def shorthands(args: argparse.Namespace) -> dict[str, str | None]:
    keys = ("character", "sensors", "observers", "scene", "algorithm", "motions", "seed")
    return {key: getattr(args, key, None) for key in keys}


def load_from_args(args: argparse.Namespace, registry: Registry):
    from retarget.recipe import load
    return load(args.recipe, registry, shorthands=shorthands(args), assignments=args.assignments)


def add_parser(sub: argparse._SubParsersAction) -> None:
    parser = sub.add_parser("recipe", help="validate, show or describe recipes")
    nested = parser.add_subparsers(dest="recipe_verb", required=True)
    validate = nested.add_parser("validate", help="check a recipe against installed plugins")
    add_recipe_flags(validate)
    validate.set_defaults(handler=run_validate)
    show = nested.add_parser("show", help="print the recipe with every default filled in")
    add_recipe_flags(show)
    show.add_argument("--format", choices=("yaml", "json"), default="yaml")
    show.set_defaults(handler=run_show)
    schema = nested.add_parser("schema", help="JSON Schema of recipes (installed plugins)")
    schema.set_defaults(handler=run_schema)


def run_validate(args: argparse.Namespace, registry: Registry) -> int:
    from retarget.cli.console import out
    resolved = load_from_args(args, registry)
    n = len(resolved.components)
    out.print(f"[green]ok[/]: {resolved.source.path} ({n} components)")
    return 0


def run_show(args: argparse.Namespace, registry: Registry) -> int:
    import yaml

    from retarget.cli.console import out
    data = load_from_args(args, registry).to_dict()
    if args.format == "json":
        out.print_json(json.dumps(data))
    else:
        print(yaml.safe_dump(data, sort_keys=False), end="")
    return 0


def run_schema(args: argparse.Namespace, registry: Registry) -> int:
    from retarget.recipe import recipe_schema
    print(json.dumps(recipe_schema(registry), indent=2))
    return 0
