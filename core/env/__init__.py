"""The tracking environment: reference, observations, managers and the ``VecEnv``."""

from __future__ import annotations

from typing import TYPE_CHECKING

from retarget.lazy import lazy_exports

if TYPE_CHECKING:
    from retarget.env.env import RetargetEnv, random_actions
    from retarget.settings.env import EnvOptions

__getattr__ = lazy_exports(
    __name__,
    {
        "EnvOptions": "retarget.settings.env",
        "RetargetEnv": "retarget.env.env",
        "random_actions": "retarget.env.env",
    },
)

__all__ = ["EnvOptions", "RetargetEnv", "random_actions"]
