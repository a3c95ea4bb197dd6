"""``retarget pretrained``: the models shipped in the package, their cards and directories."""

from __future__ import annotations

import argparse

from retarget.registry import Registry


def add_parser(sub: argparse._SubParsersAction) -> None:
    parser = sub.add_parser(
        "pretrained",
        help="list the shipped pretrained models (use one as pretrained:NAME anywhere a run "
        "directory goes)",
    )
    parser.add_argument(
        "action", nargs="?", choices=("list", "path", "show"), default="list",
        help="list (default), path NAME (its run directory), show NAME (its model card)",
    )  # fmt: skip
    parser.add_argument("name", nargs="?", help="a model name from the list")
    parser.set_defaults(handler=run)


def run(args: argparse.Namespace, registry: Registry) -> int:
    from rich import box
    from rich.table import Table

    from retarget import pretrained
    from retarget.cli.console import out
    from retarget.errors import RetargetError
    from retarget.train.package_model import render

    if args.action == "list":
        t = Table(title="pretrained models (use as pretrained:NAME)", box=box.SIMPLE_HEAD)
        for col in ("name", "character", "sensors", "algorithm", "samples", "CPU-h", "MB",
                    "summary"):  # fmt: skip
            t.add_column(col, justify="right" if col in ("samples", "CPU-h", "MB") else "left")
        for name in pretrained.names():
            c = pretrained.card(name)
            size = sum(f.stat().st_size for f in pretrained.model_dir(name).rglob("*")
                       if f.is_file())  # fmt: skip
            t.add_row(name, c.character, ",".join(c.sensors), c.algorithm,
                      f"{c.env_steps / 1e6:.1f} M", f"{c.cpu_hours:.1f}", f"{size / 1e6:.1f}",
                      c.summary)  # fmt: skip
        out.print(t)
        return 0
    if not args.name:
        raise RetargetError(f"retarget pretrained {args.action} needs a model NAME",
                            hint="`retarget pretrained` lists them")  # fmt: skip
    if args.action == "path":
        print(pretrained.model_dir(args.name))
        return 0
    print(render(pretrained.card(args.name)))
    return 0
