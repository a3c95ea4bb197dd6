"""Learning algorithms' building blocks: networks, normalisers, rollout storage and PPO.

The algorithm *plugins* (``retarget.plugins.algorithms``) are thin wrappers around these, so a
third-party algorithm can reuse any part of them.
"""

from __future__ import annotations

from retarget.learn.columns import NamedColumns, source_columns
from retarget.learn.config import PPOConfig
from retarget.learn.networks import Critic, GaussianActor, mlp
from retarget.learn.normalizer import GroupNormalizer, RunningNormalizer
from retarget.learn.ppo import PPOLearner, torch_threads
from retarget.learn.storage import RolloutStorage, gae

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
