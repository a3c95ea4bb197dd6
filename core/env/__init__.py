"""The tracking environment: reference, observations, managers and the ``VecEnv``."""

from __future__ import annotations

from retarget.env.env import EnvOptions, RetargetEnv, random_actions

__all__ = ["EnvOptions", "RetargetEnv", "random_actions"]
