"""``retarget serve RUN``: drive a trained student live from a headset stream (WebSocket)."""

from __future__ import annotations

import argparse

from retarget.commands.numbers import amount, count
from retarget.registry import Registry


def add_parser(sub: argparse._SubParsersAction) -> None:
    parser = sub.add_parser("serve", help="drive a run live from a headset stream (WebSocket)")
    parser.add_argument("run", help="run directory of a student (hmd / three_point sensors)")
    parser.add_argument("--host", default="127.0.0.1",
                        help="interface to listen on (default: this machine only)")  # fmt: skip
    parser.add_argument("--port", type=count(1, 65535), default=8765, help="TCP port")
    parser.add_argument("--seconds", type=amount(0.0, 1e7), default=None,
                        help="stop after this long (default: until Ctrl-C)")  # fmt: skip
    parser.set_defaults(handler=run)


def build_server(path: str, registry: Registry):
    """The live server of a run (loaded for one environment over a short idle clip)."""
    from retarget.live.server import LiveServer
    from retarget.live.session import LiveSession
    from retarget.motion.procedural import idle_clip
    from retarget.train.load import load_run

    loaded = load_run(path, registry, num_envs=1, clips=[idle_clip(4.0)])
    hz = loaded.env.sim.settings.control_hz
    return LiveServer(LiveSession(loaded), hz, loaded.env.character.name)


def run(args: argparse.Namespace, registry: Registry) -> int:
    import asyncio
    import contextlib
    import json

    from retarget.cli.console import out
    from retarget.live.server import serve_forever

    server = build_server(args.run, registry)

    def ready(ws) -> None:
        out.print(f"serving {args.run} on ws://{args.host}:{args.port} "
                  f"({server.character}, {server.hz:.0f} Hz); Ctrl-C stops")  # fmt: skip

    async def main() -> None:
        if args.seconds is not None:
            asyncio.get_running_loop().call_later(args.seconds, server.stop)
        await serve_forever(server, args.host, args.port, ready)

    with contextlib.suppress(KeyboardInterrupt):  # Ctrl-C: the sockets close on the way out
        asyncio.run(main())
    out.print(json.dumps(server.stats.summary()))
    return 0
