"""Videos show each environment's own prop placement (mocap bodies), not the model default."""

from __future__ import annotations

import mujoco
import numpy as np
import torch

from retarget.env import EnvOptions, RetargetEnv
from retarget.motion.procedural import default_motions
from retarget.plugins.characters.human import Human
from retarget.plugins.scenes.flat import Flat
from retarget.plugins.scenes.path_boxes import PathBoxes
from retarget.render.policy_video import copy_env_pose, render_rollout

(WALK,) = default_motions(names=("walk",))


def _frame(scene) -> tuple[RetargetEnv, np.ndarray]:
    env = RetargetEnv(Human(), [WALK], scene=scene, options=EnvOptions(num_envs=1))
    policy = lambda obs: torch.zeros(1, env.action_dim)  # noqa: E731
    frames = render_rollout(env, policy, 0, start=100, seconds=0.03, width=160, height=120)
    return env, frames[-1].astype(int)


def test_rendered_frame_shows_the_envs_boxes() -> None:
    boxes = PathBoxes(PathBoxes.Config(count=16, clear=0.4, ahead=False))
    env, with_boxes = _frame(boxes)
    _, flat = _frame(Flat())
    # the same character pose (the boxes are clear of it): only the boxes differ
    changed = (np.abs(with_boxes - flat).max(-1) > 10).sum()  # a dim scene: boxes are dark
    assert changed > 500, changed
    data = mujoco.MjData(env.world.model)
    copy_env_pose(env, 0, data)
    np.testing.assert_allclose(data.mocap_pos, env.sim.raw("mocap_pos")[0])
    near = np.linalg.norm(data.mocap_pos[:, :2] - data.qpos[:2], axis=-1)
    assert near.min() < 3.0  # placed by the episode, not parked 50 m away as in the model
