"""The ego_cameras sensor: images of the reference frame each environment is at."""

from __future__ import annotations

import numpy as np
import torch

from retarget.env import EnvOptions, RetargetEnv
from retarget.motion.camera_rigs import RIGS
from retarget.motion.procedural import default_motions
from retarget.plugins.characters.human import Human
from retarget.plugins.sensors.devices import Hmd
from retarget.plugins.sensors.ego_cameras import EgoCameras
from retarget.render.ego import EgoRenderer

WALK = [next(c for c in default_motions() if c.name.startswith("walk"))]


def test_each_env_sees_the_render_of_its_own_reference_frame() -> None:
    clean = EgoCameras(EgoCameras.Config(rig="aria", width=32, height=24, brightness=0.0,
                                         noise=0.0))  # fmt: skip
    env = RetargetEnv(Human(), WALK, sensors=[Hmd(), clean],
                      options=EnvOptions(num_envs=3, groups={"actor": ["hmd", "ego_cameras"]}))
    env.reset()
    obs, *_ = env.step(torch.zeros(3, env.action_dim))
    ctx = env.last_context
    views = clean.observe(ctx)
    assert views.shape == (3, 2, 24, 32)
    assert obs["actor"].shape == (3, env.observation_size("hmd") + 2 * 24 * 32)
    lib = env.library
    with EgoRenderer(RIGS["aria"], 32, 24) as render:
        for i, row in enumerate(ctx.ref.rows.tolist()):
            direct = render(lib.global_pos[row].numpy(), lib.devices[row, 0].numpy(),
                            float(lib.heights[0]))  # fmt: skip
            np.testing.assert_allclose(views[i].numpy(), direct / 255.0, atol=1e-6)


def test_augmentation_varies_with_the_step_but_not_with_the_batch() -> None:
    noisy = EgoCameras(EgoCameras.Config(rig="aria", width=32, height=24))
    env = RetargetEnv(Human(), WALK, sensors=[noisy],
                      options=EnvOptions(num_envs=4, groups={"actor": ["ego_cameras"]}))
    env.reset()
    env.step(torch.zeros(4, env.action_dim))
    ctx = env.last_context
    full = noisy.observe(ctx)
    assert torch.equal(noisy.observe(ctx.select(torch.tensor([2, 0]))), full[[2, 0]])
    later = type(ctx)(**{**ctx.__dict__, "episode_step": ctx.episode_step + 1})
    assert not torch.equal(noisy.observe(later), full)
    assert float(full.min()) >= 0.0 and float(full.max()) <= 1.0
