"""What a headset's cameras see of the person wearing it: grayscale images per camera.

The reference person is drawn as shaped capsules with the clip's own proportions (thicker
torso and thighs, thinner forearms; a head the headset sits in front of), on a checkered floor,
from each camera of a :class:`~retarget.motion.camera_rigs.CameraRig` mounted at the headset
pose. This is SimXR's input: the images come from the *reference* motion, rendered once per
clip frame (:mod:`retarget.render.ego_cache`), not from the simulated body. Lighting is a
headlight with shadows and reflections off, which keeps a small frame at a few milliseconds on
a CPU (OSMesa).
"""

from __future__ import annotations

from types import TracebackType

import numpy as np

from retarget.motion import skeleton as sk
from retarget.motion.camera_rigs import CameraRig
from retarget.render.gl import ensure_offscreen

_SCENE = """
<mujoco>
  <visual>
    <global offwidth="{w}" offheight="{h}"/>
    <quality shadowsize="0"/>
    <headlight ambient="0.45 0.45 0.45" diffuse="0.6 0.6 0.6" specular="0 0 0"/>
  </visual>
  <asset>
    <texture name="grid" type="2d" builtin="checker" rgb1="0.75 0.75 0.75" rgb2="0.45 0.45 0.45"
             width="64" height="64"/>
    <material name="grid" texture="grid" texrepeat="8 8" texuniform="true"/>
  </asset>
  <worldbody>
    <geom type="plane" size="30 30 5" material="grid"/>
    <body name="headset" mocap="true">
{cameras}
    </body>
  </worldbody>
</mujoco>
"""

BONE_RADIUS: dict[str, float] = {
    "spine": 0.075, "chest": 0.085, "neck": 0.045, "hip": 0.07, "knee": 0.055, "ankle": 0.04,
    "toe": 0.03, "collar": 0.05, "shoulder": 0.045, "elbow": 0.038, "wrist": 0.03,
}  # fmt: skip
"""Capsule radius (metres, for a 1.75 m person) of the bone ending at a joint whose name
contains the key; the default is 0.04. Scaled with the clip's height."""
SKIN = (0.82, 0.72, 0.62, 1.0)


def _radius(joint: str) -> float:
    for key, value in BONE_RADIUS.items():
        if key in joint:
            return value
    return 0.04


class EgoRenderer:
    """Renders a rig's views of one pose at a time; ``with EgoRenderer(...) as r: r(...)``."""

    def __init__(self, rig: CameraRig, width: int, height: int) -> None:
        import mujoco

        ensure_offscreen()
        cams = "\n".join(
            f'      <camera name="{c.name}" pos="{c.pos[0]} {c.pos[1]} {c.pos[2]}" '
            f'quat="{" ".join(str(v) for v in c.quat())}" fovy="{c.fovy}"/>'
            for c in rig.cameras
        )
        self.rig, self.width, self.height = rig, width, height
        self.model = mujoco.MjModel.from_xml_string(_SCENE.format(w=width, h=height, cameras=cams))
        self.data = mujoco.MjData(self.model)
        self.renderer = mujoco.Renderer(self.model, height, width)
        flags = self.renderer.scene.flags
        flags[mujoco.mjtRndFlag.mjRND_SHADOW] = 0
        flags[mujoco.mjtRndFlag.mjRND_REFLECTION] = 0
        self._capsule = mujoco.mjtGeom.mjGEOM_CAPSULE
        self._sphere = mujoco.mjtGeom.mjGEOM_SPHERE

    def __enter__(self) -> EgoRenderer:
        return self

    def __exit__(
        self,
        kind: type[BaseException] | None,
        value: BaseException | None,
        tb: TracebackType | None,
    ) -> None:
        self.close()

    def close(self) -> None:
        self.renderer.close()

    def __call__(self, joints: np.ndarray, headset: np.ndarray, body_height: float) -> np.ndarray:
        """Grayscale views ``(C, H, W)`` uint8 of the person at joint positions ``(J, 3)``
        (canonical skeleton, world frame) wearing the headset at ``headset`` (pos + wxyz)."""
        import mujoco

        from retarget.render.motion import add_decor_geom

        self.data.mocap_pos[0] = headset[:3]
        self.data.mocap_quat[0] = headset[3:]
        mujoco.mj_kinematics(self.model, self.data)
        mujoco.mj_camlight(self.model, self.data)
        scale = body_height / sk.REFERENCE_HEIGHT
        views = []
        for cam in self.rig.cameras:
            self.renderer.update_scene(self.data, camera=cam.name)
            scene = self.renderer.scene
            for j in range(1, sk.NUM_JOINTS):
                a, b = joints[sk.PARENTS[j]], joints[j]
                r = _radius(sk.JOINT_NAMES[j]) * scale
                if np.linalg.norm(b - a) > 1e-4:
                    add_decor_geom(mujoco, scene, self._capsule, [r], a, SKIN, b)
                add_decor_geom(mujoco, scene, self._sphere, [r], b, SKIN)
            head = joints[sk.joint_index("head")] + np.array([0.0, 0.0, 0.08]) * scale
            add_decor_geom(mujoco, scene, self._sphere, [0.1 * scale], head, SKIN)
            rgb = self.renderer.render()
            views.append((rgb @ np.array([0.299, 0.587, 0.114])).astype(np.uint8))
        return np.stack(views)
