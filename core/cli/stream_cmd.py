"""``retarget stream REC.jsonl --to URL``: replay a recording to ``retarget serve``."""

from __future__ import annotations

import argparse

from retarget.commands.numbers import amount, count
from retarget.registry import Registry


def add_parser(sub: argparse._SubParsersAction) -> None:
    parser = sub.add_parser("stream", help="replay a device recording to a live server")
    parser.add_argument("recording", help="device recording (.jsonl)")
    parser.add_argument("--to", default="ws://127.0.0.1:8765", help="the server's URL")
    parser.add_argument("--speed", type=amount(0.01, 100.0), default=1.0,
                        help="times real time")  # fmt: skip
    parser.add_argument("--viewers", type=count(0, 64), default=0,
                        help="extra connections that only watch (load testing)")  # fmt: skip
    parser.add_argument("--json", dest="json_out", help="write the statistics here")
    parser.set_defaults(handler=run)


def run(args: argparse.Namespace, registry: Registry) -> int:
    import asyncio
    import json
    from pathlib import Path

    from retarget.cli.console import out
    from retarget.errors import RetargetError
    from retarget.live.replay import replay

    try:
        stats = asyncio.run(replay(args.recording, args.to, speed=args.speed,
                                   viewers=args.viewers))  # fmt: skip
    except OSError as exc:
        raise RetargetError(f"cannot reach {args.to}: {exc}",
                            hint="start `retarget serve RUN` first") from None  # fmt: skip
    text = json.dumps(stats, indent=1)
    if args.json_out:
        Path(args.json_out).write_text(text)
    out.print(text)
    return 0
