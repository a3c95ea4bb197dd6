"""``retarget play RUN [RUN...] --motions CLIP --out X.gif``: videos of trained policies, and of
pose estimators (the character placed in the estimate each frame)."""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import TYPE_CHECKING

from retarget.cli.run_changes import add_run_change_args
from retarget.commands.numbers import amount, count, image_size
from retarget.errors import RetargetError, require_extra
from retarget.kinds.capabilities import Acting, Exportable, PoseEstimating, require
from retarget.registry import Registry

if TYPE_CHECKING:
    from retarget.motion.device_recording import DeviceRecording


PLAYS = "play shows a policy driving physics or a pose estimator's estimate"

def add_parser(sub: argparse._SubParsersAction) -> None:
    parser = sub.add_parser("play", help="render a trained policy (several runs side by side)")
    parser.add_argument("runs", nargs="+", help="run directories (runs/NAME/latest)")
    parser.add_argument("--motions", help="clip to play (default: the run's first clip)")
    parser.add_argument(
        "--clip", type=count(0, 10**6), default=0, help="index of the clip when a directory"
    )
    parser.add_argument(
        "--out", required=True, help="output .gif, .mp4 or .png (8 frames, one sheet)"
    )
    parser.add_argument(
        "--seconds", type=amount(0.0, 600.0), default=8.0, help="length of the rollout"
    )
    parser.add_argument(
        "--start",
        type=amount(0.0, 1e5, inclusive=True),
        default=0.0,
        help="start time in the clip, s",
    )
    parser.add_argument(
        "--size", type=image_size, default="480x360", help="WIDTHxHEIGHT of each view"
    )
    parser.add_argument("--ghost-offset", type=float, default=0.0, help="ghost shift, m")
    parser.add_argument(
        "--azimuth",
        type=float,
        default=135.0,
        help="camera direction, degrees in the world frame (90: along +y)",
    )
    parser.add_argument("--elevation", type=float, default=-15.0,
                        help="camera elevation, degrees (negative: from above)")  # fmt: skip
    parser.add_argument(
        "--input",
        metavar="RECORDING",
        help="drive the policy from a recorded device stream (.jsonl) instead of --motions",
    )
    parser.add_argument(
        "--cameras",
        action="store_true",
        help="draw the policy's camera images (what it read) beside each character",
    )
    add_run_change_args(parser)
    parser.set_defaults(handler=run)


def _changes(args: argparse.Namespace) -> dict:
    """``--scene``/``--set`` as :func:`load_run` keywords."""
    return {"scene": args.scene, "assignments": args.assignments}


def _driven_by(rec: DeviceRecording, path: str, registry: Registry, args: argparse.Namespace):
    """A run whose env's only clip carries the recording's devices (at the control rate,
    calibrated to the character's start) over a standing idle body (start pose only); sensors
    that read recorded streams get the recording's camera frames."""
    import numpy as np
    import torch

    from retarget.eval.recorded import drive_recordings

    try:
        drive = drive_recordings(path, registry, [rec], changes=_changes(args))
    except ValueError as exc:
        raise RetargetError(f"{args.input}: {exc}") from None
    hz = drive.loaded.env.sim.settings.control_hz
    args.seconds = min(args.seconds, (drive.lengths[0] - 1) / hz)
    args.start = args.start + drive.lead / hz  # the rollout starts at the first sample
    times = rec.time[0] + np.arange(drive.lengths[0]) / hz
    _replay_recorded(drive.loaded.env, torch.as_tensor(drive.rows[0]), rec, times, args.input)
    return drive.loaded, f"recording {Path(args.input).name}"


def _replay_recorded(env, rows, rec: DeviceRecording, times, path: str) -> None:
    """Hand the sensors that read recorded streams (camera images) what the recording holds
    for each control step: the latest frame taken by then."""
    from retarget import RecordedStream
    from retarget.motion.device_frames import frames_path

    for sensor in env.sensors:
        if sensor.recorded is None:
            continue
        if sensor.recorded != "images":
            raise RetargetError(
                f"the run's sensor '{sensor.name}' reads a recorded {sensor.recorded!r} stream; "
                "device recordings hold poses and camera images only"
            )
        if rec.frames is None:
            raise RetargetError(
                f"{path} has no camera frames, but the run's '{sensor.name}' sensor reads the "
                "headset's images",
                hint=f"record them into {frames_path(path)} (see `retarget motion record`)",
            )
        picks = rec.frames.latest(times)
        sensor.replay(
            rows,
            RecordedStream(rec.frames.images[picks], {"rig": rec.frames.rig}, frames_path(path)),
        )


def follow_summary(gaps: list[float], hz: float, lost_at: float = 0.5) -> str:
    """How well an avatar followed a recorded headset: its head's distance to the headset,
    and when it first lost it (SimXR's failure rule: farther than ``lost_at`` metres)."""
    import numpy as np

    g = np.asarray(gaps)
    lost = np.flatnonzero(g > lost_at)
    end = (f"lost it at {lost[0] / hz:.1f} s (head over {lost_at} m away)" if lost.size
           else f"followed to the end (head within {lost_at} m every frame)")  # fmt: skip
    return (f"head to headset {100 * g.mean():.0f} cm mean, {100 * g.max():.0f} cm max over "
            f"{len(g) / hz:.1f} s; {end}")


def run(args: argparse.Namespace, registry: Registry) -> int:
    import numpy as np

    from retarget.cli.console import out
    from retarget.learn.columns import image_inputs
    from retarget.motion.device_recording import read_recording
    from retarget.render.character_view import label, save_video
    from retarget.render.estimate_video import Shot, render_estimate
    from retarget.render.obs_views import image_panel
    from retarget.render.policy_video import render_rollout
    from retarget.train.load import load_run

    width, height = args.size
    if Path(args.out).suffix.lower() == ".mp4":  # named before anything is rendered
        require_extra("video", "imageio", "imageio_ffmpeg", needed_for="writing .mp4")
    if args.input and args.motions:
        raise RetargetError("give --input RECORDING or --motions CLIP, not both")
    stream = read_recording(args.input) if args.input else None
    views = []
    for path in args.runs:
        if stream is not None:
            loaded, clip_name = _driven_by(stream, path, registry, args)
        else:
            loaded = load_run(path, registry, num_envs=1, motions=args.motions, **_changes(args))
        env = loaded.env
        if not 0 <= args.clip < env.library.num_clips:
            raise RetargetError(f"--clip {args.clip}: the motions hold {env.library.num_clips}")
        start = round(args.start * env.sim.settings.control_hz)
        algorithm = loaded.algorithm
        if isinstance(algorithm, PoseEstimating) and not isinstance(algorithm, Acting):
            if stream is not None or args.cameras:
                raise RetargetError(
                    f"{path} is a pose estimator: it plays motion clips (--motions), with the "
                    "character placed in its estimate; --input and --cameras drive a policy")
            shot = Shot(width, height, args.azimuth, args.elevation, args.ghost_offset)
            frames = render_estimate(env, algorithm.pose_estimator(), args.clip, start=start,
                                     seconds=args.seconds, shot=shot)  # fmt: skip
            name = f"{env.character.name}: {env.library.names[args.clip]} (estimate)"
            views.append([label(f, [(0.5, 0.06, name)]) for f in frames])
            continue
        group = require(loaded.algorithm, Exportable).policy()[0] if args.cameras else "actor"
        images = image_inputs(env, group) if args.cameras else ()
        if args.cameras and not images:
            raise RetargetError(
                f"--cameras: {path} reads no camera images (its '{group}' observation has no "
                "image source)", hint="train with --sensors hmd,ego_cameras",
            )  # fmt: skip
        observed: list[np.ndarray] = []
        gaps: list[float] = []
        frames = render_rollout(
            env,
            require(loaded.algorithm, Acting, hint=PLAYS).act,
            args.clip,
            start=start,
            seconds=args.seconds,
            azimuth=args.azimuth,
            elevation=args.elevation,
            width=width,
            height=height,
            ghost_offset=args.ghost_offset,
            ghost=stream is None,
            observed=observed if images else None,
            group=group,
            head_gap=gaps if stream is not None else None,
        )
        if gaps:
            out.print(f"{path}: {follow_summary(gaps, env.sim.settings.control_hz)}")
        if images:
            frames = [
                np.concatenate([f, image_panel(o, images, f.shape[0])], axis=1)
                for f, o in zip(frames, observed, strict=True)
            ]
        clip = clip_name if stream is not None else env.library.names[args.clip]
        name = f"{env.character.name}: {clip}"
        views.append([label(f, [(0.5, 0.06, name)]) for f in frames])
    count = min(len(v) for v in views)
    frames = [np.concatenate([v[i] for v in views], axis=1) for i in range(count)]
    out_path = Path(args.out)
    written = save_video(frames, out_path, fps=float(env.sim.settings.control_hz))
    out.print(f"wrote {out_path} ({written})")
    return 0
