"""``retarget plugins`` and ``retarget plugins show KIND NAME``."""

from __future__ import annotations

import argparse
import inspect
import json

from retarget.registry import Registry


def add_parser(sub: argparse._SubParsersAction) -> None:
    parser = sub.add_parser("plugins", help="list installed plugins and who provides them")
    parser.add_argument("--json", action="store_true", help="machine-readable output")
    parser.set_defaults(handler=run_list)
    nested = parser.add_subparsers(dest="plugins_verb")
    show = nested.add_parser("show", help="a plugin's documentation and config fields")
    show.add_argument("kind", help="plugin kind, e.g. character, reward, sensor")
    show.add_argument("name", help="plugin name")
    show.set_defaults(handler=run_show)


def run_list(args: argparse.Namespace, registry: Registry) -> int:
    from rich.markup import escape
    from rich.table import Table

    from retarget.cli.console import out
    if args.json:
        rows = [
            {
                "kind": e.kind,
                "name": e.name,
                "aliases": list(e.aliases),
                "distribution": e.distribution,
                "version": e.version,
                "entry_point": e.plugin,
                "summary": e.cls.summary(),
            }
            for e in registry
        ]
        out.print_json(json.dumps(rows))
        return 0
    table = Table(title="retarget plugins", show_lines=False)
    for col in ("kind", "name", "distribution", "version"):
        table.add_column(col, no_wrap=True)
    table.add_column("summary", overflow="fold", ratio=1)
    for e in registry:
        label = e.name + (f" ({', '.join(e.aliases)})" if e.aliases else "")
        table.add_row(e.kind, label, e.distribution, e.version, escape(e.cls.summary()))
    out.print(table)
    return 0


def run_show(args: argparse.Namespace, registry: Registry) -> int:
    from rich.markup import escape
    from rich.table import Table

    from retarget.cli.console import out
    entry = registry.get(args.kind, args.name)
    cls = entry.cls
    out.print(f"[bold]{entry.kind} {entry.name}[/]  ({cls.__module__}.{cls.__qualname__})")
    out.print(f"provided by {escape(entry.provider)}")
    doc = inspect.cleandoc(cls.__doc__ or "(no docstring)")
    out.print(escape(doc))
    if entry.cls.requires:
        out.print(f"requires: {', '.join(entry.cls.requires)}")
    if entry.kind == "algorithm":
        from retarget.kinds.capabilities import capabilities

        out.print(f"capabilities: {', '.join(capabilities(entry.cls)) or '(none)'}")
    fields = cls.Config.model_fields
    if not fields:
        out.print("config: (no fields)")
        return 0
    table = Table(title="config")
    for col in ("field", "type", "default", "description"):
        table.add_column(col, overflow="fold")
    for name, info in fields.items():
        default = (
            "(required)"
            if info.is_required()
            else repr(info.get_default(call_default_factory=True))
        )
        annotation = getattr(info.annotation, "__name__", None) or str(info.annotation)
        table.add_row(name, escape(annotation), escape(default), escape(info.description or ""))
    out.print(table)
    return 0
