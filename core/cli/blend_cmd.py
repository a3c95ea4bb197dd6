"""``retarget blend TUNED --start RUN --weight W --out DIR``: one policy between a fine-tune and
the run it started from (:mod:`retarget.train.blend`)."""

from __future__ import annotations

import argparse

from retarget.registry import Registry


def add_parser(sub: argparse._SubParsersAction) -> None:
    parser = sub.add_parser(
        "blend", help="a run directory whose policy lies between a fine-tune and its start"
    )
    parser.add_argument("run", help="the fine-tuned run (a directory or pretrained:NAME)")
    parser.add_argument("--start", required=True,
                        help="the run it was fine-tuned from (its --init-from)")  # fmt: skip
    parser.add_argument("--weight", type=float, default=0.5,
                        help="share of the fine-tune: 0 is the start, 1 the fine-tune")  # fmt: skip
    parser.add_argument("--out", required=True, help="new run directory to write")
    parser.set_defaults(handler=run)


def run(args: argparse.Namespace, registry: Registry) -> int:
    from retarget.cli.console import out
    from retarget.train.blend import BLENDED_FROM, blend_runs

    # loading both runs (their environments and clips) takes a minute on a laptop
    with out.status(f"loading {args.run} and {args.start}"):
        target = blend_runs(args.run, args.start, args.weight, args.out, registry)
    out.print(f"wrote {target} ({args.weight:g} of the fine-tune; {target / BLENDED_FROM})")
    return 0
