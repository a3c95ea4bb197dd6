"""Learning algorithms' building blocks: networks, normalisers, rollout storage and PPO.

The algorithm *plugins* (``retarget.plugins.algorithms``) are thin wrappers around these, so a
third-party algorithm can reuse any part of them.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from retarget.lazy import lazy_exports

if TYPE_CHECKING:
    from retarget.learn.columns import NamedColumns, source_columns
    from retarget.learn.config import PPOConfig
    from retarget.learn.networks import Critic, GaussianActor, mlp
    from retarget.learn.normalizer import GroupNormalizer, RunningNormalizer
    from retarget.learn.ppo import PPOLearner
    from retarget.learn.storage import RolloutStorage, gae
    from retarget.learn.threads import torch_threads

__getattr__ = lazy_exports(
    __name__,
    {
        "NamedColumns": "retarget.learn.columns",
        "source_columns": "retarget.learn.columns",
        "PPOConfig": "retarget.learn.config",
        "Critic": "retarget.learn.networks",
        "GaussianActor": "retarget.learn.networks",
        "mlp": "retarget.learn.networks",
        "GroupNormalizer": "retarget.learn.normalizer",
        "RunningNormalizer": "retarget.learn.normalizer",
        "PPOLearner": "retarget.learn.ppo",
        "torch_threads": "retarget.learn.threads",
        "RolloutStorage": "retarget.learn.storage",
        "gae": "retarget.learn.storage",
    },
)

__all__ = [
    "Critic",
    "GaussianActor",
    "GroupNormalizer",
    "NamedColumns",
    "PPOConfig",
    "PPOLearner",
    "RolloutStorage",
    "RunningNormalizer",
    "gae",
    "mlp",
    "source_columns",
    "torch_threads",
]
