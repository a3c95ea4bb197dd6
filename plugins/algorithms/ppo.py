"""PPO as an algorithm plugin (defaults: paper Table 3; env count measured on this machine)."""

from __future__ import annotations

from collections.abc import Mapping
from typing import TYPE_CHECKING, Any

import retarget
from retarget import VecEnv
from retarget.learn.config import PPOConfig
from retarget.learn.delegating import LearnerAlgorithm

if TYPE_CHECKING:
    import torch

    from retarget.learn.ppo import PPOLearner


class PPO(LearnerAlgorithm[PPOConfig]):
    """Proximal policy optimisation with an asymmetric critic and fixed exploration noise.

    The actor reads the ``actor`` observation group, the critic the privileged ``critic``
    group; observations and values are normalised with running statistics; time-outs are
    bootstrapped from ``info["final_obs"]``, failures are not. ``rollout_steps`` x the
    recipe's ``env.num_envs`` samples make one iteration.
    """

    name = "ppo"

    def __init__(self, config: PPOConfig | None = None) -> None:
        super().__init__(config)
        self.learner: PPOLearner | None = None

    def setup(self, env: VecEnv, generator: torch.Generator | None = None) -> None:
        from retarget.learn.columns import image_inputs, residual_columns
        from retarget.learn.ppo import PPOLearner
        c = self.config
        residual = residual_columns(env, c.actor_group, c.residual, self.name)
        groups = (self.config.actor_group, self.config.critic_group)
        images = {g: image_inputs(env, g) for g in groups}
        self.learner = PPOLearner(
            self.config, env.obs_dims, env.action_dim, env.num_envs, generator, residual, images,
            comm=self.comm,
        )

    def fresh_rank(self, generator: torch.Generator) -> None:
        self._ready().fresh_rank(generator)

    def warm_start(self, state: Mapping[str, Any], inputs: Mapping[str, torch.Tensor]) -> None:
        self._ready().warm_start(state, inputs)


@retarget.hookimpl
def register_algorithms(register) -> None:
    register(PPO)
