"""``retarget motion``: inspect motion files and render them to pictures."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path
from typing import TYPE_CHECKING

import retarget
from retarget import Command, MotionError, RetargetError
from retarget.commands.numbers import MAX_PIXELS, MIN_PIXELS, count, image_size
from retarget.errors import require_extra

if TYPE_CHECKING:
    from retarget.kinds.lookup import PluginLookup
    from retarget.motion.clip import MotionClip


def _add_format_args(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--format", dest="motion_format", metavar="NAME",
                        help="read with this motion format (default: by suffix)")  # fmt: skip
    parser.add_argument("--joints", metavar="NAMES.txt",
                        help="position-only files: joint names, one per line")  # fmt: skip
    parser.add_argument("--fps", dest="source_fps", type=float,
                        help="position-only files: the capture's frame rate")  # fmt: skip


def _formats(args: argparse.Namespace, registry: PluginLookup) -> dict:
    """The readers the flags ask for, from the invocation's registry (never reloaded)."""
    chosen = getattr(args, "motion_format", None)
    joints, fps = getattr(args, "joints", None), getattr(args, "source_fps", None)
    if chosen is None and (joints is not None or fps is not None):
        chosen = "positions"
    if chosen is not None:
        entry = registry.get("motion_format", chosen)
        settings = {k: v for k, v in (("joints", joints), ("fps", fps)) if v is not None}
        try:
            config = entry.cls.Config.model_validate(settings)
        except ValueError as exc:
            raise RetargetError(f"--format {chosen}: {exc}") from None
        return {chosen: entry.cls(config)}
    return registry.motion_formats()


def _read(path: str, formats: dict) -> MotionClip:
    from retarget.motion.sources import read_file

    p = Path(path)
    if not p.is_file():
        raise MotionError("no such file", file=p)
    return read_file(p, formats)


class MotionCommand(Command):
    """Inspect motion files (frames, rate, skeleton, height, contacts) or render a clip.

    ``retarget motion inspect FILE...`` prints one table row per file;
    ``retarget motion show FILE --out clip.png`` writes a contact sheet of evenly spaced frames
    (``.mp4`` needs the optional ``imageio-ffmpeg`` package).
    ``retarget motion generate --out DIR [--names sit_stand ...]`` writes the project's generated
    clips as BVH files, so that a subset (e.g. only sitting) can be given to ``--motions``.
    ``retarget motion record FILE --out me.jsonl [--cameras quest2]`` writes the device stream
    a headset would record of the clip (and its cameras' frames), for ``retarget play --input``.
    """

    name = "motion"
    help = "inspect and render motion clips"

    def add_arguments(self, parser: argparse.ArgumentParser) -> None:
        sub = parser.add_subparsers(dest="motion_action", metavar="ACTION", required=True)
        inspect = sub.add_parser("inspect", help="table of clip facts")
        inspect.add_argument("files", nargs="+", metavar="FILE", help="motion files to describe")
        _add_format_args(inspect)
        show = sub.add_parser("show", help="render a clip to .png (frame grid) or .mp4")
        show.add_argument("file", metavar="FILE", help="the motion file to draw")
        _add_format_args(show)
        show.add_argument("--out", required=True, help="output .png or .mp4")
        show.add_argument("--frames", type=count(1, 64), default=8, help="frames in a .png grid")
        show.add_argument(
            "--cameras",
            choices=("quest2", "aria"),
            help="draw what a headset's cameras see instead (.png: a row of views per frame)",
        )
        show.add_argument(
            "--size",
            type=count(MIN_PIXELS, MAX_PIXELS),
            default=320,
            help="pixels per frame (square)",
        )
        show.add_argument("--start", type=float, default=0.0, help="first second to show")
        show.add_argument("--end", type=float, default=None, help="last second to show")
        show.add_argument(
            "--view",
            choices=("side", "front"),
            default="side",
            help="camera beside the direction of travel, or in front",
        )
        gen = sub.add_parser("generate", help="write the generated default clips as BVH")
        gen.add_argument("--out", required=True, help="directory for NAME.bvh files")
        gen.add_argument(
            "--names", nargs="+", default=None, help="clips to write (default: all of them)"
        )
        gen.add_argument("--height", type=float, default=None, help="subject height, m")
        rec = sub.add_parser(
            "record", help="write what a headset would record of a clip (.jsonl [+ frames])"
        )
        rec.add_argument("file", metavar="FILE", help="the motion file the person performs")
        _add_format_args(rec)
        rec.add_argument("--out", required=True, help="output .jsonl (frames: NAME.frames.npz)")
        rec.add_argument(
            "--cameras", choices=("quest2", "aria"), help="also record this rig's camera frames"
        )
        rec.add_argument("--size", type=image_size, default="40x30",
                         help="WIDTHxHEIGHT of each camera frame")  # fmt: skip
        rec.add_argument(
            "--convention",
            choices=("openxr", "unity", "retarget"),
            default="openxr",
            help="coordinate convention of the poses written",
        )

    def run(self, args: argparse.Namespace) -> int:
        self.formats = _formats(args, self.plugins())
        if args.motion_action == "inspect":
            return self._inspect(args)
        if args.motion_action == "generate":
            return self._generate(args)
        if args.motion_action == "record":
            return self._record(args)
        return self._show(args)

    def _generate(self, args: argparse.Namespace) -> int:
        from retarget.motion import skeleton as sk
        from retarget.motion.bvh_write import write_bvh
        from retarget.motion.procedural import GENERATORS, default_motions

        names = tuple(args.names) if args.names else None
        try:
            clips = default_motions(args.height or sk.REFERENCE_HEIGHT, names=names)
        except KeyError:
            unknown = [n for n in names or () if n not in GENERATORS]
            raise RetargetError(
                f"unknown generated motion(s) {', '.join(unknown)}",
                hint=f"choose from {', '.join(GENERATORS)}",
            ) from None
        out = Path(args.out)
        out.mkdir(parents=True, exist_ok=True)
        for clip in clips:
            path = write_bvh(clip, out / f"{clip.name}.bvh")
            print(f"wrote {path} ({clip.num_frames} frames, {clip.duration:.1f} s)")
        return 0

    def _record(self, args: argparse.Namespace) -> int:
        import numpy as np

        from retarget.motion.device_frames import RecordedFrames, frames_path
        from retarget.motion.device_recording import DeviceRecording, write_recording
        from retarget.motion.devices import device_poses

        out = Path(args.out)
        if out.suffix.lower() != ".jsonl":
            raise RetargetError(f"--out must end in .jsonl, got '{out.name}'")
        clip = _read(args.file, self.formats)
        poses = device_poses(clip.global_pos, clip.global_rot, clip.height)
        times = np.arange(clip.num_frames) / clip.fps
        frames = None
        if args.cameras:
            from retarget.motion.camera_rigs import RIGS
            from retarget.render.ego_cache import render_into

            rig = RIGS[args.cameras]
            width, height = args.size
            images = np.zeros((clip.num_frames, len(rig.cameras), height, width), np.uint8)
            heights = np.full(clip.num_frames, clip.height)
            render_into(images, clip.global_pos, poses[:, 0], heights, rig)
            frames = RecordedFrames(times, images, rig.model_dump_json())
        tracked = np.ones(poses.shape[:2], dtype=bool)
        out.parent.mkdir(parents=True, exist_ok=True)
        write_recording(out, DeviceRecording(times, poses, tracked, frames), args.convention)
        also = f" and {frames_path(out)} ({args.cameras}, {args.size[0]}x{args.size[1]})"
        print(f"wrote {out} ({clip.num_frames} samples, {clip.duration:.1f} s, "
              f"{args.convention}){also if frames else ''}")  # fmt: skip
        return 0

    def _inspect(self, args: argparse.Namespace) -> int:
        import numpy as np
        from rich.console import Console
        from rich.table import Table

        table = Table(title="motion clips")
        for col in (
            "file",
            "frames",
            "fps",
            "seconds",
            "skeleton",
            "height m",
            "contact L",
            "contact R",
            "units",
            "up",
        ):
            table.add_column(col, justify="left" if col in ("file", "skeleton") else "right")
        from retarget.motion.sources import expand

        suffixes = [x for fmt in self.formats.values() for x in fmt.suffixes]
        files = expand(args.files, suffixes)  # folders and archives: the files they hold
        seconds = 0.0
        for f in files:
            clip = _read(str(f), self.formats)
            seconds += clip.duration
            c = clip.contacts if clip.contacts is not None else np.zeros((1, 2))
            table.add_row(
                Path(f).name,
                str(clip.num_frames),
                f"{clip.fps:g}",
                f"{clip.duration:.2f}",
                clip.skeleton,
                f"{clip.height:.2f}",
                f"{c[:, 0].mean():.2f}",
                f"{c[:, 1].mean():.2f}",
                str(clip.meta.get("units", "-")),
                str(clip.meta.get("up", "-")),
            )
        # full names and numbers even when piped (rich would squeeze the table to 80 columns)
        console = Console(soft_wrap=True, width=None if sys.stdout.isatty() else 200)
        console.print(table)
        if len(files) > 1:
            console.print(f"{len(files)} clips, {seconds / 3600:.2f} hours")
        return 0

    def _show(self, args: argparse.Namespace) -> int:
        import numpy as np

        from retarget.render.motion import contact_sheet, render_frames, write_png

        out = Path(args.out)
        suffix = out.suffix.lower()
        if suffix not in (".png", ".mp4"):
            raise RetargetError(f"--out must end in .png or .mp4, got '{out.name}'")
        if suffix == ".mp4":  # named before any clip is read or rendered
            require_extra("video", "imageio_ffmpeg", needed_for="writing .mp4")
        clip = _read(args.file, self.formats)
        first = int(np.clip(round(args.start * clip.fps), 0, clip.num_frames - 1))
        last = (
            clip.num_frames - 1
            if args.end is None
            else int(np.clip(round(args.end * clip.fps), first, clip.num_frames - 1))
        )
        if args.cameras:
            if suffix != ".png":
                raise RetargetError("--cameras draws a .png sheet", hint="use --out views.png")
            shown = max(1, min(args.frames, last - first + 1))
            picks = np.linspace(first, last, shown).round().astype(int)
            views = _camera_views(clip, picks, args.cameras, args.size)
            write_png(out, contact_sheet(views, columns=views.shape[0] // shown))
            print(
                f"wrote {out} ({shown} frames x {views.shape[0] // shown} {args.cameras} "
                f"cameras, of {last - first + 1} frames)"
            )
            return 0
        boxes = _scene_boxes(clip)
        if suffix == ".png":
            count = max(1, min(args.frames, last - first + 1))
            frames = np.linspace(first, last, count).round().astype(int)
            images = render_frames(clip, frames, width=args.size, height=args.size,
                                   view=args.view, boxes=boxes)  # fmt: skip
            write_png(out, contact_sheet(images, columns=min(4, count)))
            what = f"{count}-frame sheet of {last - first + 1} frames"
        else:
            import imageio_ffmpeg

            step = max(1, round(clip.fps / 30.0))
            frames = np.arange(first, last + 1, step)
            images = render_frames(clip, frames, width=args.size, height=args.size,
                                   view=args.view, boxes=boxes)  # fmt: skip
            writer = imageio_ffmpeg.write_frames(
                str(out), (args.size, args.size), fps=clip.fps / step
            )
            writer.send(None)
            for img in images:
                writer.send(np.ascontiguousarray(img))
            writer.close()
            what = f"{len(images)} frames at {clip.fps / step:.0f} fps"
        print(f"wrote {out} ({what}{f', {len(boxes)} scene boxes' if boxes else ''})")
        return 0


@retarget.hookimpl
def register_commands(register) -> None:
    register(MotionCommand)


def _scene_boxes(clip) -> list:
    """The boxes of the scene recorded with a clip (a mesh beside its file), if any."""
    if clip.source is None or not clip.source.parent.is_dir():
        return []
    from retarget.scene.mesh_boxes import boxes_from_mesh, mesh_beside

    mesh = mesh_beside(clip.source)
    return boxes_from_mesh(mesh) if mesh is not None else []


def _camera_views(clip, picks, rig_name: str, size: int):
    """``(K * C, H, W, 3)`` grayscale views of the rig's cameras at frames ``picks``."""
    import numpy as np

    from retarget.motion.camera_rigs import RIGS
    from retarget.motion.devices import device_poses
    from retarget.render.ego import EgoRenderer

    rig = RIGS[rig_name]
    headsets = device_poses(clip.global_pos, clip.global_rot, clip.height)[:, 0]
    width, height = size, max(16, size * 3 // 4)
    with EgoRenderer(rig, width, height) as render:
        views = [render(clip.global_pos[f], headsets[f], clip.height) for f in picks]
    gray = np.concatenate(views)  # (K * C, H, W)
    return np.repeat(gray[..., None], 3, axis=-1)
