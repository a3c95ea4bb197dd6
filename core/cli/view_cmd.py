"""``retarget view TARGET...``: clips, policy rollouts or a live session in the browser."""

from __future__ import annotations

import argparse
from pathlib import Path

from retarget.commands.numbers import amount, count
from retarget.errors import RetargetError, require_extra
from retarget.registry import Registry


def add_parser(sub: argparse._SubParsersAction) -> None:
    parser = sub.add_parser("view", help="3D viewer in the browser: clips, runs, live sessions")
    parser.add_argument("targets", nargs="+", metavar="RUN|CLIP",
                        help="run directories and/or motion files (one selector)")  # fmt: skip
    parser.add_argument("--motions", help="clip a run is rolled out on (default: its first)")
    parser.add_argument("--seconds", type=amount(0.5, 600.0), default=10.0,
                        help="length of each run's rollout")  # fmt: skip
    parser.add_argument("--joints", help="position-only clips: joint names, one per line")
    parser.add_argument("--source-fps", type=float, help="position-only clips: their rate")
    parser.add_argument("--live", metavar="URL",
                        help="follow a `retarget serve` session (one RUN)")  # fmt: skip
    parser.add_argument("--host", default="127.0.0.1", help="interface (default: this machine)")
    parser.add_argument("--port", type=count(1, 65535), default=8080, help="HTTP port")
    parser.add_argument("--stop-after", type=amount(0.0, 1e7), default=None,
                        help="close after this many seconds (default: Ctrl-C)")  # fmt: skip
    parser.set_defaults(handler=run)


def run(args: argparse.Namespace, registry: Registry) -> int:
    import contextlib

    from retarget.cli.console import out
    from retarget.render.browser_view import Viewer, clip_track, follow_live, run_track
    from retarget.train.load import load_run
    from retarget.train.run_dir import resolve_run

    require_extra("live", "viser", "websockets", needed_for="retarget view")

    def is_run(target: str) -> bool:
        return Path(target).is_dir()

    if args.live:
        runs = [t for t in args.targets if is_run(t)]
        if len(runs) != 1:
            raise RetargetError("--live follows one run's character: give exactly one RUN")
        loaded = load_run(resolve_run(runs[0]), registry, num_envs=1)
        out.print(f"viewer on http://{args.host}:{args.port} following {args.live}")
        with contextlib.suppress(KeyboardInterrupt):
            follow_live(args.live, loaded, args.host, args.port, args.stop_after)
        return 0
    tracks = []
    for target in args.targets:
        if is_run(target):
            loaded = load_run(resolve_run(target), registry, num_envs=1, motions=args.motions)
            tracks.append(run_track(target, loaded, args.seconds))
        else:
            from retarget.motion.sources import read_clip

            clip = read_clip(target, joints=args.joints, fps=args.source_fps,
                             formats=registry.motion_formats())
            tracks.append(clip_track(target, clip))
    viewer = Viewer(tracks, args.host, args.port)
    out.print(f"viewer on http://{args.host}:{args.port} ({len(tracks)} tracks); Ctrl-C stops")
    with contextlib.suppress(KeyboardInterrupt):
        viewer.play(args.stop_after)
    viewer.server.stop()
    return 0
