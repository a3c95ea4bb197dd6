"""``retarget character ...``: look at characters and at kinematic retargeting.

``retarget character show NAME --out rest.png`` renders a character's rest pose with its role
sites (headset, controllers, root) visible. ``retarget character retarget CLIP --character NAME
--out clip.gif`` renders the human of the clip beside the kinematically retargeted character
(the paper's Fig. 4, left and middle), and prints how often joint limits clipped the angles.
"""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Any

import retarget
from retarget import Command, RetargetError
from retarget.character.builder import geom_z_extent
from retarget.commands.numbers import image_size


def _parse_sets(pairs: list[str]) -> dict[str, Any]:
    """``key=value`` pairs (values parsed as YAML scalars) into a config dict."""
    import yaml

    out: dict[str, Any] = {}
    for pair in pairs:
        key, sep, value = pair.partition("=")
        if not sep:
            raise RetargetError(f"--set expects key=value, got {pair!r}")
        out[key.strip()] = yaml.safe_load(value)
    return out


def _character(registry: Any, name: str, config: dict[str, Any]) -> Any:
    cls = registry.get("character", name).cls
    try:
        return cls(cls.Config.model_validate(config))
    except ValueError as exc:
        raise RetargetError(f"bad --set for character '{name}': {exc}") from None


def _read_clip(path: Path, formats: Any, joints: str | None = None, fps: float | None = None
               ) -> Any:  # fmt: skip
    from retarget.motion.sources import read_clip

    return read_clip(path, joints=joints, fps=fps, formats=formats)


class CharacterCommand(Command):
    """Render a character's rest pose, or a clip retargeted onto a character."""

    name = "character"
    help = "render characters and kinematic retargeting"

    def add_arguments(self, parser: argparse.ArgumentParser) -> None:
        sub = parser.add_subparsers(dest="character_command", required=True)
        show = sub.add_parser("show", help="render a character's rest pose")
        show.add_argument("name", help="character plugin name (human, jesse, dino, oppy, ...)")
        show.add_argument("--out", type=Path, required=True, help="output image (.png)")
        show.add_argument("--set", action="append", default=[], metavar="KEY=VALUE",
                          help="character config field, e.g. --set tail=fixed")
        show.add_argument("--size", type=image_size, default="960x720",
                          help="WIDTHxHEIGHT in pixels")
        ret = sub.add_parser("retarget", help="render a clip beside its kinematic retarget")
        ret.add_argument("clip", type=Path, help="motion file (.bvh, .npz, .npy)")
        ret.add_argument("--joints", help="position-only files: joint names, one per line")
        ret.add_argument("--source-fps", type=float, help="position-only files: their rate")
        ret.add_argument("--character", required=True, help="character plugin name")
        ret.add_argument("--out", type=Path, required=True, help="output (.gif, .mp4 or .png)")
        ret.add_argument("--set", action="append", default=[], metavar="KEY=VALUE",
                         help="character config field, e.g. --set tail=passive")
        ret.add_argument("--seconds", type=float, default=6.0, help="length to render")
        ret.add_argument("--start", type=float, default=0.0, help="start time in the clip, s")
        ret.add_argument("--fps", type=float, default=15.0, help="frame rate of the output")
        ret.add_argument("--size", type=image_size, default="800x480",
                         help="WIDTHxHEIGHT in pixels")
        ret.add_argument("--bend-only", action="store_true",
                         help="drive elbows by the file's bend alone, as runs recorded before "
                         "env.hinge_elbows did (default: elbows as hinges, as training does)")

    def run(self, args: argparse.Namespace) -> int:
        width, height = args.size
        registry = self.plugins()
        character = _character(registry, args.name if args.character_command == "show"
                               else args.character, _parse_sets(args.set))
        args.out.parent.mkdir(parents=True, exist_ok=True)
        if args.character_command == "show":
            show(character, args.out, width, height)
        else:
            clip = _read_clip(args.clip, registry.motion_formats(), args.joints,
                              args.source_fps)
            if not args.bend_only:
                from retarget.motion.hinge_elbows import hinge_elbows

                clip = hinge_elbows(clip)
            info = retarget_video(character, clip, args.out, width, height,
                                  seconds=args.seconds, start=args.start, fps=args.fps)
            print(f"{character.name}: root scale {info['root_scale']:.3f}, joint-limit "
                  f"clipping {100 * info['clip_rate']:.2f}% of mapped angles")
            print(f"wrote {args.out} ({info['written']})")
            return 0
        print(f"wrote {args.out}")
        return 0


def show(character: Any, out: Path, width: int = 960, height: int = 720) -> None:
    """Rest pose with sites, labelled with name, height, mass, links and DoF."""
    import mujoco

    from retarget.render import character_view as cv

    spec = character.build_spec()
    model = cv.scene_with([(character.name, spec)], spacing=0.0)
    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)
    image = cv.render(model, data, cv.fit_camera(model, data), width, height, sites=True)
    own = spec.compile()
    low, high = _extent(own)
    nact = own.nu
    text = (f"{character.name}: {high - low:.2f} m, {own.body_mass.sum():.1f} kg, "
            f"{own.nbody - 1} links, {own.nv - 6} DoF ({nact} actuated)")
    cv.save_image(cv.label(image, [(0.5, 0.05, text)]), out)


def _extent(model: Any) -> tuple[float, float]:
    import mujoco


    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)
    return geom_z_extent(model, data)


def retarget_video(character: Any, clip: Any, out: Path, width: int, height: int, *,
                   seconds: float, start: float, fps: float) -> dict[str, Any]:
    """Human (the ``human`` character at the subject's height) beside the retargeted character."""
    import mujoco
    import numpy as np

    from retarget.character import kinematic as km
    from retarget.plugins.characters.human import Human, HumanConfig
    from retarget.render import character_view as cv

    human = Human(HumanConfig(height=float(np.clip(clip.height, 0.6, 2.4))))
    h_model = human.build_spec().compile()
    c_model = character.build_spec().compile()
    h_motion = km.retarget_clip(clip, h_model, human.joint_map(), root_scale=1.0 *
                                km.root_height_ratio(h_model, clip))
    c_motion = km.retarget_clip(clip, c_model, character.joint_map())
    # Side by side, walking from the same start: the character stands to the human's right.
    width_h = 1.2 * max(_half_width(h_model), 0.3)
    spacing = width_h + 1.2 * max(_half_width(c_model), 0.3)
    model = cv.scene_with([("human", human.build_spec()),
                           (character.name, character.build_spec())], spacing)
    data = mujoco.MjData(model)
    first = int(start * clip.fps)
    stop = min(clip.num_frames, first + int(seconds * clip.fps))
    picks = np.arange(first, stop, max(1, round(clip.fps / fps)))
    if picks.size == 0:
        raise RetargetError(f"clip has {clip.num_frames} frames; nothing after {start} s")
    origin = clip.root_pos[first, :2].copy()
    nh = h_model.nq
    mujoco.mj_forward(model, data)
    cam = cv.fit_camera(model, data)
    frames = []
    with cv.FrameRenderer(model, width, height) as render:
        for i in picks:
            qh = h_motion.qpos[i].copy()
            qc = c_motion.qpos[i].copy()
            qh[:2] -= origin * 1.0 * h_motion.root_scale
            qc[:2] -= origin * c_motion.root_scale
            qc[1] -= spacing
            data.qpos[:nh] = qh
            data.qpos[nh:] = qc
            mujoco.mj_kinematics(model, data)
            cam.lookat[:2] = (qh[:2] + qc[:2]) / 2
            frames.append(cv.label(render(data, cam), [(0.5, 0.06, f"human  |  {character.name}"
                                                        " (kinematic retarget)")]))
    written = cv.save_video(frames, out, fps)
    return {"written": written, "frames": float(len(frames)), "root_scale": c_motion.root_scale,
            "clip_rate": c_motion.clip_rate}


def _half_width(model: Any) -> float:
    """Half the lateral extent of a model at rest (to space characters side by side)."""
    import mujoco
    import numpy as np

    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)
    ids = [g for g in range(model.ngeom) if model.geom_bodyid[g] != 0]
    y = data.geom_xpos[ids, 1]
    r = model.geom_rbound[ids]
    return float(max(np.max(y + r), -np.min(y - r)))


@retarget.hookimpl
def register_commands(register) -> None:
    register(CharacterCommand)
