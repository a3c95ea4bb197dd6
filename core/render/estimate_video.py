"""Videos of a pose estimator: the character placed in its estimate every frame, the true
motion as a ghost skeleton and the devices it read as yellow boxes (``retarget play EST``).

An estimator drives no physics, so there is no rollout: the clip's estimate (causal, each
frame from its own device window, :func:`retarget.eval.kinematic.estimate_library`) is put on
the character exactly as ``retarget eval`` measures it, and each frame is drawn as a policy
video's is (:class:`retarget.render.policy_video.FrameView`).
"""

from __future__ import annotations

from dataclasses import dataclass

import mujoco
import numpy as np
import torch

from retarget.env import RetargetEnv
from retarget.env.reference import CharacterReference
from retarget.eval.kinematic import estimate_library
from retarget.kinds.pose_estimator import PoseEstimator
from retarget.render.character_view import FrameRenderer
from retarget.render.policy_video import FrameView


@dataclass(frozen=True)
class Shot:
    """Picture size (pixels), camera direction (degrees, world frame) and the ghost's
    sideways shift (m) of a video."""

    width: int = 480
    height: int = 360
    azimuth: float = 135.0
    elevation: float = -15.0
    ghost_offset: float = 0.0


def render_estimate(
    env: RetargetEnv, estimator: PoseEstimator, clip: int, *, start: int = 0,
    seconds: float = 8.0, shot: Shot = Shot(),
) -> list[np.ndarray]:  # fmt: skip
    """Every control step of ``clip`` from frame ``start``, ``seconds`` long, with the
    character in ``estimator``'s estimate (its motions are ``env``'s library)."""
    lib = env.library
    steps = int(min(seconds * env.sim.settings.control_hz, int(lib.length[clip]) - 1 - start))
    estimate = estimate_library(env, estimator)
    placed = CharacterReference(env.character, env.world.model, env.layout, estimate.clips,
                                hinge=env.options.hinge_elbows)  # fmt: skip
    model = env.world.model
    data = mujoco.MjData(model)
    first = int(lib.start[clip]) + start
    nq = placed.qpos64.shape[1]
    top = float(placed.pose(torch.tensor([first])).body_pos[0, :, 2].max())
    view = FrameView(env, top, shot.azimuth, shot.elevation, shot.ghost_offset)
    frames = []
    with FrameRenderer(model, shot.width, shot.height) as render:
        for row in range(first + 1, first + 1 + max(steps, 1)):
            data.qpos[:nq] = placed.qpos64[row]
            mujoco.mj_kinematics(model, data)
            frames.append(view.draw(render, data, row))
    return frames
