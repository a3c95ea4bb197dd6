"""An algorithm plugin whose work is done by a learner object.

PPO, DAgger and behaviour cloning keep their state in a learner (``retarget.learn.ppo``,
``retarget.learn.dagger``, ...) made in ``setup``; the plugin only prepares recipes and loads
what the learner needs. This base forwards the rest of the algorithm contract to it, so the
forwarding is written once.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import TYPE_CHECKING, Any

from retarget.errors import PluginError
from retarget.kinds.algorithm import Algorithm
from retarget.kinds.base import ConfigT
from retarget.kinds.iteration import IterationResult

if TYPE_CHECKING:
    import torch

    from retarget.kinds.algorithm import VecEnv


class LearnerAlgorithm(Algorithm[ConfigT]):
    """Forwards training, acting, the deployable policy and checkpoints to ``self.learner``
    (set by the subclass's ``setup``), whose ``actor_key`` names the observation group the
    policy reads and whose ``deployable_policy()`` is the exported module."""

    learner: Any = None

    def _ready(self) -> Any:
        if self.learner is None:
            raise PluginError("setup(env) must be called first", plugin=self.name)
        return self.learner

    def train_iteration(self, env: VecEnv) -> IterationResult:
        return IterationResult(stats=self._ready().train_iteration(env))

    def act(self, obs: Mapping[str, torch.Tensor]) -> torch.Tensor:
        return self._ready().act(obs)

    def policy(self) -> tuple[str, torch.nn.Module]:
        learner = self._ready()
        return learner.actor_key, learner.deployable_policy()

    def state_dict(self) -> dict[str, Any]:
        return self._ready().state_dict()

    def load_state_dict(self, state: Mapping[str, Any]) -> None:
        self._ready().load_state_dict(state)
