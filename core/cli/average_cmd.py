"""``retarget average RUN --last N [--upto ITER] --out DIR``: one policy from the mean of a
run's last checkpoints, or of those up to one chosen earlier (:mod:`retarget.train.average`)."""

from __future__ import annotations

import argparse

from retarget.registry import Registry


def add_parser(sub: argparse._SubParsersAction) -> None:
    parser = sub.add_parser(
        "average", help="a run directory whose policy is the mean of a run's last checkpoints"
    )
    parser.add_argument("run", help="run directory (runs/NAME/latest)")
    parser.add_argument("--last", type=int, default=20,
                        help="how many of the newest checkpoints to average")  # fmt: skip
    parser.add_argument("--upto", type=int, default=None, metavar="ITER",
                        help="average the --last checkpoints up to this iteration's (a "
                        "checkpoint chosen in a run that went on past it)")  # fmt: skip
    parser.add_argument("--out", required=True, help="new run directory to write")
    parser.set_defaults(handler=run)


def run(args: argparse.Namespace, registry: Registry) -> int:
    from retarget.cli.console import out
    from retarget.train.average import AVERAGED_FROM, average_run

    target = average_run(args.run, args.out, args.last, args.upto)
    out.print(f"wrote {target} (the mean of {args.last} checkpoints; {target / AVERAGED_FROM})")
    return 0
