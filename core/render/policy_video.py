"""Videos of a policy: the simulated character, the human reference as a ghost skeleton, and
the user's devices as markers, rendered offscreen (OSMesa on CPU) for people to look at."""

from __future__ import annotations

from collections.abc import Callable, Mapping

import mujoco
import numpy as np
import torch

from retarget.env import RetargetEnv
from retarget.eval.metrics import head_to_headset
from retarget.motion import skeleton as sk
from retarget.render.character_view import FrameRenderer
from retarget.render.motion import add_decor_geom

GHOST = (0.2, 0.45, 0.95, 0.55)
DEVICE = (1.0, 0.85, 0.1, 1.0)


def copy_env_pose(env: RetargetEnv, index: int, data: mujoco.MjData) -> None:
    """Pose ``data`` as environment ``index`` is: every joint (character and scene props)
    and the mocap bodies, which hold that environment's own prop placement (the model's
    mocap poses are only the default placement: boxes on a path are parked far away there);
    then forward kinematics for drawing."""
    data.qpos[:] = env.sim.raw("qpos")[index]
    data.mocap_pos[:] = env.sim.raw("mocap_pos")[index]
    data.mocap_quat[:] = env.sim.raw("mocap_quat")[index]
    mujoco.mj_kinematics(env.world.model, data)


def render_rollout(
    env: RetargetEnv,
    policy: Callable[[Mapping[str, torch.Tensor]], torch.Tensor],
    clip: int,
    *,
    start: int = 0,
    seconds: float = 8.0,
    width: int = 480,
    height: int = 360,
    ghost_offset: float = 0.0,
    ghost: bool = True,
    azimuth: float = 135.0,
    elevation: float = -15.0,
    observed: list[np.ndarray] | None = None,
    group: str = "actor",
    head_gap: list[float] | None = None,
) -> list[np.ndarray]:
    """Run ``policy`` in environment 0 from ``(clip, start)`` and render every control step.

    The ghost is the human reference motion (shifted sideways by ``ghost_offset`` metres,
    overlaid when 0; ``ghost=False`` hides it, e.g. when the devices come from a recording);
    yellow boxes are the headset and controllers the policy was given. The camera follows the
    character from ``azimuth``/``elevation`` (degrees, world frame; 90 looks along +y).
    ``observed``, when given, receives environment 0's ``group`` observation of every frame
    (what the policy read), e.g. to draw its camera views beside the video. ``head_gap``,
    when given, receives each step's distance (m) from environment 0's simulated head to the
    headset it was given: what a person wearing that headset sees of their avatar.
    """
    model = env.world.model
    data = mujoco.MjData(model)
    lib = env.library
    steps = int(min(seconds * env.sim.settings.control_hz, int(lib.length[clip]) - 1 - start))
    n = env.num_envs
    obs = env.place(torch.full((n,), clip), torch.full((n,), start))
    top = float(env.sim.state.body_pos[0, :, 2].max())
    view = FrameView(env, top, azimuth, elevation, ghost_offset, ghost)
    head = env.layout.site("head")
    frames = []
    with FrameRenderer(model, width, height) as render, torch.no_grad():
        for _ in range(max(steps, 1)):
            if observed is not None:
                observed.append(obs[group][0].float().numpy().copy())
            obs, *_ = env.step(policy(obs))
            if head_gap is not None and env.last_context is not None:
                head_gap.append(
                    float(head_to_headset(env.last_context, head, env.headset_mount)[0])
                )
            row = int(lib.rows(env.clip[:1], env.frame[:1])[0, 0])
            copy_env_pose(env, 0, data)
            frames.append(view.draw(render, data, row))
    return frames


class FrameView:
    """How every frame of a video is drawn: a camera following the character (framed by its
    height ``top`` at the start: the Dino is 2.5 m, the human 1.75 m), the library's human
    motion at that frame as a ghost skeleton (shifted sideways by ``ghost_offset``; none when
    ``ghost`` is false) and its devices as yellow boxes."""

    def __init__(self, env: RetargetEnv, top: float, azimuth: float, elevation: float,
                 ghost_offset: float = 0.0, ghost: bool = True) -> None:  # fmt: skip
        self.lib, self.top, self.ghost = env.library, top, ghost
        self.cam = mujoco.MjvCamera()
        self.cam.type = mujoco.mjtCamera.mjCAMERA_FREE
        self.cam.distance = 4.0 * max(1.0, top / 1.8)
        self.cam.elevation, self.cam.azimuth = elevation, azimuth
        self.shift = np.array([0.0, ghost_offset, 0.0])
        # the training world has only MuJoCo's default headlight, which renders dim: light
        # the video like `character show` does (visual settings only; physics reads none)
        model = env.world.model
        model.vis.headlight.ambient[:] = [0.45, 0.45, 0.45]
        model.vis.headlight.diffuse[:] = [0.6, 0.6, 0.6]
        model.vis.headlight.specular[:] = [0.1, 0.1, 0.1]

    def draw(self, render: FrameRenderer, data: mujoco.MjData, row: int) -> np.ndarray:
        """The image of ``data`` (kinematics done) at library ``row``."""
        self.cam.lookat[:] = [data.qpos[0], data.qpos[1], 0.5 * self.top]
        render.renderer.update_scene(data, camera=self.cam)
        scene = render.renderer.scene
        human = self.lib.global_pos[row].numpy() + self.shift
        for j in range(1, sk.NUM_JOINTS if self.ghost else 1):
            a, b = human[sk.PARENTS[j]], human[j]
            add_decor_geom(mujoco, scene, mujoco.mjtGeom.mjGEOM_CAPSULE, [0.025], a, GHOST, b)
        for d in self.lib.devices[row].numpy():
            add_decor_geom(mujoco, scene, mujoco.mjtGeom.mjGEOM_BOX, [0.035] * 3, d[:3], DEVICE)
        return render.renderer.render().copy()
