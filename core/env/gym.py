"""A gymnasium ``VectorEnv`` view of :class:`RetargetEnv` (install the ``gym`` extra).

Other RL libraries can train on retarget's environments through it. Observations are the
``actor`` group (or another group by name) as float32 numpy arrays; actions are in [-1, 1].
Environments reset themselves inside ``step`` (gymnasium's "same step" autoreset): a finished
environment's row already holds its next episode's first observation, and
``infos["final_obs"]`` holds the observation it ended in when it timed out.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import torch

try:
    import gymnasium
    from gymnasium.vector import AutoresetMode, VectorEnv
except ImportError as exc:  # pragma: no cover - exercised only without the extra
    from retarget.errors import MissingExtra

    raise MissingExtra(
        "retarget.env.gym needs gymnasium, which is not installed",
        hint="pip install 'retarget[gym]'",
    ) from exc

from retarget.env.env import RetargetEnv


class GymVectorEnv(VectorEnv):
    """Gymnasium vector-env adapter over a :class:`RetargetEnv`."""

    metadata = {"autoreset_mode": AutoresetMode.SAME_STEP}

    def __init__(self, env: RetargetEnv, group: str = "actor") -> None:
        if group not in env.obs_dims:
            raise KeyError(f"no observation group '{group}'; known: {', '.join(env.obs_dims)}")
        self.env, self.group = env, group
        self.num_envs = env.num_envs
        dim = env.obs_dims[group]
        self.single_observation_space = gymnasium.spaces.Box(-np.inf, np.inf, (dim,), np.float32)
        self.single_action_space = gymnasium.spaces.Box(-1.0, 1.0, (env.action_dim,), np.float32)
        self.observation_space = gymnasium.vector.utils.batch_space(
            self.single_observation_space, self.num_envs
        )
        self.action_space = gymnasium.vector.utils.batch_space(
            self.single_action_space, self.num_envs
        )

    def reset(
        self, *, seed: int | None = None, options: dict[str, Any] | None = None
    ) -> tuple[np.ndarray, dict[str, Any]]:
        if seed is not None:
            self.env.generator.manual_seed(seed)
        obs = self.env.reset()
        return obs[self.group].numpy().copy(), {}

    def step(
        self, actions: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, dict[str, Any]]:
        obs, reward, terminated, truncated, info = self.env.step(torch.as_tensor(actions))
        infos: dict[str, Any] = {"nan_resets": info["nan_resets"]}
        if "final_obs" in info:
            infos["final_obs"] = info["final_obs"][self.group].numpy().copy()
        if "episode" in info:
            infos["episode"] = {k: v for k, v in info["episode"].items() if k != "terms"}
        return (
            obs[self.group].numpy().copy(),
            reward.numpy().astype(np.float64),
            terminated.numpy().copy(),
            truncated.numpy().copy(),
            infos,
        )
