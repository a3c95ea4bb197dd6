"""The gymnasium adapter presents RetargetEnv with gymnasium's spaces and step contract."""

from __future__ import annotations

import numpy as np
import pytest

gymnasium = pytest.importorskip("gymnasium", reason="the 'gym' extra is not installed")

from retarget.env.build import env_from_recipe  # noqa: E402
from retarget.env.gym import GymVectorEnv  # noqa: E402
from retarget.recipe import load  # noqa: E402
from retarget.registry.loader import load_plugins  # noqa: E402


def test_gym_vector_env_contract() -> None:
    env = env_from_recipe(load(None, load_plugins(strict=True)), num_envs=3, threads=1)
    venv = GymVectorEnv(env)
    obs, _ = venv.reset(seed=0)
    assert venv.observation_space.contains(obs)
    for _ in range(5):
        action = venv.action_space.sample()
        obs, reward, terminated, truncated, _ = venv.step(action)
        assert obs.shape == (3, env.obs_dims["actor"]) and obs.dtype == np.float32
        assert reward.shape == (3,) and np.isfinite(reward).all()
        assert terminated.dtype == bool and truncated.dtype == bool
    with pytest.raises(KeyError, match="known"):
        GymVectorEnv(env, group="student")
