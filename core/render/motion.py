"""Offscreen pictures of a clip: the skeleton as capsules on a checker floor (MuJoCo).

Used by ``retarget motion show`` to eyeball what a reader produced (upright? facing forward?
feet on the floor? left and right the right way round?). Bones are drawn as capsules added to
the scene per frame, so no model has to be compiled per clip; left limbs are blue, right
limbs red, the spine grey, and a foot in contact gets a green ball under its ankle.
Without a display it renders through OSMesa (CPU), or EGL when ``MUJOCO_GL=egl``.
"""

from __future__ import annotations

import struct
import zlib
from collections.abc import Sequence
from pathlib import Path

import numpy as np

from retarget.motion import skeleton as sk
from retarget.motion.clip import MotionClip
from retarget.motion.devices import device_poses
from retarget.render.gl import ensure_offscreen

_SCENE = """
<mujoco>
  <visual>
    <global offwidth="{w}" offheight="{h}"/>
    <headlight ambient="0.35 0.35 0.35" diffuse="0.5 0.5 0.5"/>
  </visual>
  <asset>
    <texture name="grid" type="2d" builtin="checker" rgb1="0.82 0.82 0.82" rgb2="0.62 0.62 0.62"
             width="256" height="256"/>
    <texture name="sky" type="skybox" builtin="gradient" rgb1="0.85 0.9 1" rgb2="1 1 1" width="32"
             height="32"/>
    <material name="grid" texture="grid" texrepeat="2 2" texuniform="true"/>
  </asset>
  <worldbody>
    <light pos="0 0 6" dir="0 0 -1" directional="true" diffuse="0.6 0.6 0.6"/>
    <geom type="plane" size="40 40 5" material="grid" rgba="0.8 0.8 0.8 1"/>
  </worldbody>
</mujoco>
"""

_LEFT = (0.2, 0.4, 0.9, 1.0)
_RIGHT = (0.9, 0.25, 0.2, 1.0)
_MID = (0.55, 0.55, 0.55, 1.0)
_DEVICE = (1.0, 0.85, 0.1, 1.0)
_BOX = (0.62, 0.5, 0.38, 0.85)


def _color(j: int) -> tuple[float, ...]:
    name = sk.JOINT_NAMES[j]
    return _LEFT if name.startswith("left") else _RIGHT if name.startswith("right") else _MID


def add_decor_geom(
    mujoco,
    scene,
    kind: int,
    size: list[float],
    at: np.ndarray,
    rgba: tuple[float, ...],
    to: np.ndarray | None = None,
    mat: np.ndarray | None = None,
) -> None:
    """Append one decorative geom (a connector capsule when ``to`` is given; turned by
    ``mat`` otherwise) to a scene."""
    if scene.ngeom >= scene.maxgeom:
        return
    geom = scene.geoms[scene.ngeom]
    mujoco.mjv_initGeom(
        geom,
        kind,
        np.array(size + [0.0] * (3 - len(size))),
        at,
        (np.eye(3) if mat is None else np.asarray(mat, dtype=np.float64)).ravel(),
        np.array(rgba, dtype=np.float32),
    )
    if to is not None:
        mujoco.mjv_connector(geom, kind, size[0], at, to)
    scene.ngeom += 1


def render_frames(
    clip: MotionClip,
    frames: np.ndarray,
    *,
    width: int = 320,
    height: int = 320,
    azimuth: float | None = None,
    view: str = "side",
    devices: bool = True,
    boxes: Sequence = (),
) -> np.ndarray:
    """RGB images ``(K, height, width, 3)`` of the given frames, camera following the pelvis.

    ``view="side"`` looks at the body from its side relative to the clip's direction of travel
    (so walking goes left to right in the picture), ``"front"`` from straight ahead;
    ``azimuth`` in degrees (MuJoCo's free camera) overrides both. ``boxes``: the scene's
    upright boxes (``position``, ``yaw``, ``size``, ``height``: e.g. a clip's recorded props).
    """
    import mujoco

    ensure_offscreen()
    model = mujoco.MjModel.from_xml_string(_SCENE.format(w=width, h=height))
    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)  # world geom frames (the floor) are set by kinematics
    pos = clip.global_pos
    if azimuth is None:
        travel = pos[-1, 0, :2] - pos[0, 0, :2]
        if np.linalg.norm(travel) < 0.3:
            fwd = np.array([1.0, 0.0, 0.0])
            from retarget.geometry import rotations as rot

            fwd = rot.apply(clip.global_rot[0, 0], fwd)
            travel = fwd[:2]
        offset = {"side": 90.0, "front": 180.0}[view]
        azimuth = float(np.degrees(np.arctan2(travel[1], travel[0]))) + offset
    dev = device_poses(pos, clip.global_rot, clip.height) if devices else None
    renderer = mujoco.Renderer(model, height, width)
    try:
        cam = mujoco.MjvCamera()
        cam.type = mujoco.mjtCamera.mjCAMERA_FREE
        cam.distance = 3.2 * clip.height / sk.REFERENCE_HEIGHT
        cam.elevation = -12.0
        cam.azimuth = azimuth
        images = []
        radius = 0.03 * clip.height / sk.REFERENCE_HEIGHT
        for f in frames:
            p = pos[f]
            # at the pelvis's height over what it stands on: 0.85 m for a standing 1.75 m
            # adult on the floor, higher on a box top
            stand = 0.85 * clip.height / sk.REFERENCE_HEIGHT
            lift = max(0.0, p[0, 2] - sk.standing_pelvis_height(clip.offsets))
            cam.lookat[:] = [p[0, 0], p[0, 1], stand + lift]
            renderer.update_scene(data, camera=cam)
            scene = renderer.scene

            def add(
                kind: int,
                size: list[float],
                at: np.ndarray,
                rgba: tuple[float, ...],
                to: np.ndarray | None = None,
                scene=scene,
            ) -> None:
                add_decor_geom(mujoco, scene, kind, size, at, rgba, to)

            for box in boxes:
                c, s_ = np.cos(box.yaw), np.sin(box.yaw)
                turn = np.array([[c, -s_, 0.0], [s_, c, 0.0], [0.0, 0.0, 1.0]])
                centre = np.array([box.position[0], box.position[1], box.height / 2])
                half = [box.size[0] / 2, box.size[1] / 2, box.height / 2]
                add_decor_geom(mujoco, scene, mujoco.mjtGeom.mjGEOM_BOX, half, centre, _BOX,
                               mat=turn)  # fmt: skip
            for j in range(1, sk.NUM_JOINTS):
                a, b = p[sk.PARENTS[j]], p[j]
                if np.linalg.norm(b - a) > 1e-4:
                    add(mujoco.mjtGeom.mjGEOM_CAPSULE, [radius], a, _color(j), b)
            for j in range(sk.NUM_JOINTS):
                add(mujoco.mjtGeom.mjGEOM_SPHERE, [radius * 1.3], p[j], _color(j))
            add(
                mujoco.mjtGeom.mjGEOM_SPHERE,
                [radius * 3.0],
                p[sk.joint_index("head")] + np.array([0, 0, 0.09]) * clip.height / 1.75,
                _MID,
            )
            for k, ankle in enumerate(sk.FEET):
                if clip.contacts[f, k]:
                    spot = p[ankle].copy()
                    spot[2] = 0.0
                    add(mujoco.mjtGeom.mjGEOM_SPHERE, [radius * 1.6], spot, (0.1, 0.8, 0.2, 1))
            if dev is not None:
                for d in range(3):
                    add(mujoco.mjtGeom.mjGEOM_BOX, [0.03, 0.03, 0.03], dev[f, d, :3], _DEVICE)
            images.append(renderer.render().copy())
    finally:
        renderer.close()
    return np.stack(images)


def contact_sheet(images: np.ndarray, columns: int = 4) -> np.ndarray:
    """Tile ``(K, H, W, 3)`` images into one picture, row by row, 4 px white gaps."""
    k, h, w, _ = images.shape
    rows = -(-k // columns)
    gap = 4
    sheet = np.full((rows * (h + gap) - gap, columns * (w + gap) - gap, 3), 255, np.uint8)
    for i, img in enumerate(images):
        r, c = divmod(i, columns)
        sheet[r * (h + gap) : r * (h + gap) + h, c * (w + gap) : c * (w + gap) + w] = img
    return sheet


def write_png(path: str | Path, image: np.ndarray) -> Path:
    """Write an RGB ``uint8`` image as PNG with zlib only (no imaging dependency)."""
    path = Path(path)
    img = np.ascontiguousarray(image, dtype=np.uint8)
    h, w, _ = img.shape
    raw = np.concatenate([np.zeros((h, 1), np.uint8), img.reshape(h, w * 3)], axis=1)

    def chunk(tag: bytes, payload: bytes) -> bytes:
        return (
            struct.pack(">I", len(payload))
            + tag
            + payload
            + struct.pack(">I", zlib.crc32(tag + payload) & 0xFFFFFFFF)
        )

    png = b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", w, h, 8, 2, 0, 0, 0))
    png += chunk(b"IDAT", zlib.compress(raw.tobytes(), 6)) + chunk(b"IEND", b"")
    path.write_bytes(png)
    return path
