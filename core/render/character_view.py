"""Offscreen pictures of characters: a rest pose, and a human beside a retargeted character.

Rendering uses MuJoCo's own renderer (OSMesa on a machine without a display, chosen by
:func:`retarget.render.gl.ensure_offscreen`). Labels are drawn with Pillow when it is installed and
skipped otherwise, so no plotting library is needed; Pillow also writes GIFs. MP4 needs
``imageio`` with ffmpeg; without it the error says to use ``.gif``.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

import mujoco
import numpy as np

from retarget.errors import RetargetError, require_extra
from retarget.render.gl import ensure_offscreen

FLOOR_RGBA = (0.82, 0.84, 0.86, 1.0)


def scene_with(specs: Sequence[tuple[str, mujoco.MjSpec]], spacing: float) -> mujoco.MjModel:
    """One world holding each character (prefixed ``<label>/``) side by side along +Y.

    Character ``i`` stands at ``y = -i * spacing`` so the first one is on the viewer's left when
    looking at the characters' faces (they face +X).
    """
    world = mujoco.MjSpec()
    world.modelname = "view"
    if specs:  # the characters' physics options, so attaching them raises no conflict
        world.option.timestep = specs[0][1].option.timestep
        world.option.integrator = specs[0][1].option.integrator
    world.visual.global_.offwidth = 1600
    world.visual.global_.offheight = 1200
    world.visual.headlight.ambient = [0.35, 0.35, 0.35]
    world.visual.headlight.diffuse = [0.5, 0.5, 0.5]
    tex = world.add_texture(
        name="grid",
        type=mujoco.mjtTexture.mjTEXTURE_2D,
        builtin=mujoco.mjtBuiltin.mjBUILTIN_CHECKER,
        width=64,
        height=64,
        rgb1=[0.78, 0.8, 0.82],
        rgb2=[0.7, 0.72, 0.74],
    )
    del tex
    world.add_material(name="grid", texrepeat=[4, 4], texuniform=True, textures=["", "grid"])
    world.worldbody.add_geom(
        type=mujoco.mjtGeom.mjGEOM_PLANE, size=[0, 0, 0.05], material="grid", rgba=list(FLOOR_RGBA)
    )
    world.worldbody.add_light(
        pos=[2, -2, 6], dir=[-0.3, 0.3, -1], diffuse=[0.6, 0.6, 0.6], castshadow=True
    )
    for i, (label, spec) in enumerate(specs):
        frame = world.worldbody.add_frame(pos=[0.0, -i * spacing, 0.0])
        world.attach(spec.copy(), prefix=f"{label}/", frame=frame)
    return world.compile()


def fit_camera(
    model: mujoco.MjModel, data: mujoco.MjData, azimuth: float = 135.0, elevation: float = -14.0
) -> mujoco.MjvCamera:
    """A free camera looking at all non-world geoms from the front-left, framing them."""
    ids = [g for g in range(model.ngeom) if model.geom_bodyid[g] != 0]
    pts = data.geom_xpos[ids]
    rad = model.geom_rbound[ids][:, None]
    lo = (pts - rad).min(0)
    hi = (pts + rad).max(0)
    cam = mujoco.MjvCamera()
    cam.type = mujoco.mjtCamera.mjCAMERA_FREE
    cam.lookat[:] = (lo + hi) / 2
    cam.distance = float(np.linalg.norm(hi - lo)) * 1.15 + 0.3
    cam.azimuth = azimuth
    cam.elevation = elevation
    return cam


def render(
    model: mujoco.MjModel,
    data: mujoco.MjData,
    cam: mujoco.MjvCamera,
    width: int = 960,
    height: int = 720,
    sites: bool = False,
) -> np.ndarray:
    """One RGB frame; the renderer is closed before returning (its GL context is freed)."""
    ensure_offscreen()
    opt = mujoco.MjvOption()
    if sites:
        opt.sitegroup[:] = 1
    renderer = mujoco.Renderer(model, height=height, width=width)
    try:
        renderer.update_scene(data, camera=cam, scene_option=opt)
        return renderer.render().copy()
    finally:
        renderer.close()


class FrameRenderer:
    """Renders many frames of one model with one renderer (closed by ``close``/context exit)."""

    def __init__(self, model: mujoco.MjModel, width: int, height: int) -> None:
        ensure_offscreen()
        self.renderer = mujoco.Renderer(model, height=height, width=width)

    def __call__(self, data: mujoco.MjData, cam: mujoco.MjvCamera) -> np.ndarray:
        self.renderer.update_scene(data, camera=cam)
        return self.renderer.render().copy()

    def close(self) -> None:
        self.renderer.close()

    def __enter__(self) -> FrameRenderer:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


def label(image: np.ndarray, texts: Sequence[tuple[float, float, str]]) -> np.ndarray:
    """Draw text at fractional positions ``(u, v)``; unchanged if Pillow is not installed."""
    try:
        from PIL import Image, ImageDraw
    except ImportError:
        return image
    img = Image.fromarray(image)
    draw = ImageDraw.Draw(img)
    size = max(12, image.shape[0] // 30)
    for u, v, text in texts:
        xy = (u * image.shape[1], v * image.shape[0])
        box = draw.textbbox(xy, text, font_size=size, anchor="mm")
        draw.rectangle((box[0] - 4, box[1] - 3, box[2] + 4, box[3] + 3), fill=(245, 245, 245))
        draw.text(xy, text, fill=(10, 10, 10), font_size=size, anchor="mm")
    return np.asarray(img)


def save_image(image: np.ndarray, path: Path) -> None:
    """PNG (or anything Pillow writes) from an RGB array; a PPM fallback needs nothing."""
    try:
        from PIL import Image
    except ImportError as exc:
        if path.suffix.lower() == ".ppm":
            h, w, _ = image.shape
            path.write_bytes(f"P6 {w} {h} 255\n".encode() + image.astype(np.uint8).tobytes())
            return
        raise RetargetError(
            f"writing {path.suffix} needs Pillow (pip install pillow)", file=path
        ) from exc
    Image.fromarray(image).save(path)


SHEET_FRAMES = 8
"""Frames in the picture a ``.png`` output of a rollout or clip gets."""


def gif_timing(count: int, fps: float) -> tuple[list[int], int]:
    """Which of ``count`` frames at ``fps`` a GIF keeps, and its frame delay in centiseconds.

    GIF delays are whole centiseconds (and players slow anything under 2 cs to 10 cs), so 36
    fps cannot be stored as is; frames are picked at the nearest representable rate so the
    GIF plays in real time rather than 1.4x too fast.
    """
    delay = max(2, round(100 / fps))
    step = fps * delay / 100.0  # source frames per GIF frame
    picks = [round(k * step) for k in range(int((count - 1) / step) + 1)]
    return [min(i, count - 1) for i in picks], delay


def save_video(frames: Sequence[np.ndarray], path: Path, fps: float) -> str:
    """GIF via Pillow, MP4 via imageio-ffmpeg if installed, PNG = a sheet of up to
    ``SHEET_FRAMES`` evenly spaced frames (what a rollout did, at a glance)."""
    suffix = path.suffix.lower()
    if suffix == ".png":
        from retarget.render.motion import contact_sheet

        picks = np.linspace(0, len(frames) - 1, min(SHEET_FRAMES, len(frames))).round()
        chosen = np.stack([frames[int(i)] for i in picks])
        save_image(contact_sheet(chosen, columns=min(4, len(chosen))), path)
        return f"{len(chosen)}-frame sheet of {len(frames)} frames"
    if suffix == ".gif":
        from PIL import Image

        picks, delay = gif_timing(len(frames), fps)
        imgs = [Image.fromarray(frames[i]) for i in picks]
        imgs[0].save(path, save_all=True, append_images=imgs[1:], duration=delay * 10, loop=0)
        return f"{len(imgs)} frames at {100 / delay:.1f} fps, real time"
    if suffix == ".mp4":
        require_extra("video", "imageio", "imageio_ffmpeg", needed_for="writing .mp4")
        import imageio.v3 as iio

        iio.imwrite(path, np.stack(frames), fps=fps, codec="libx264")
        return f"{len(frames)} frames at {fps:.0f} fps"
    raise RetargetError(f"unknown output format {suffix!r}; use .png, .gif or .mp4", file=path)
