"""``retarget recipe validate|show|schema``."""

from __future__ import annotations

import argparse
import json

from retarget.commands.recipe_args import add_recipe_flags, load_from_args
from retarget.registry import Registry


def add_parser(sub: argparse._SubParsersAction) -> None:
    parser = sub.add_parser("recipe", help="validate, show or describe recipes")
    nested = parser.add_subparsers(dest="recipe_verb", required=True)
    validate = nested.add_parser("validate", help="check a recipe against installed plugins")
    add_recipe_flags(validate)
    validate.set_defaults(handler=run_validate)
    show = nested.add_parser("show", help="print the recipe with every default filled in")
    add_recipe_flags(show)
    show.add_argument(
        "--format", choices=("yaml", "json"), default="yaml", help="output format"
    )
    show.set_defaults(handler=run_show)
    schema = nested.add_parser("schema", help="JSON Schema of recipes (installed plugins)")
    schema.set_defaults(handler=run_schema)


def run_validate(args: argparse.Namespace, registry: Registry) -> int:
    from retarget.cli.console import out
    from retarget.sim.world import build_world

    resolved = load_from_args(args, registry)
    made = {path: comp.instantiate() for path, comp in resolved.components.items()}
    build_world(made["character"], made.get("scene"))  # the character and scene compile together
    n = len(resolved.components)
    out.print(f"[green]ok[/]: {resolved.source.path} ({n} components, the world compiles)")
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
