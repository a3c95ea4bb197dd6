"""The episode length cap: a time-out, so PPO bootstraps instead of treating it as a failure."""

from __future__ import annotations

from typing import TYPE_CHECKING

from pydantic import Field

import retarget
from retarget import PluginConfig, StepContext, Termination

if TYPE_CHECKING:
    import torch


class EpisodeCapConfig(PluginConfig):
    max_steps: int = Field(
        300, gt=0, description="control steps per episode (300 = 8.3 s at 36 Hz)"
    )


class EpisodeCap(Termination[EpisodeCapConfig]):
    """Ends an episode after ``max_steps`` control steps (a truncation, not a failure)."""

    name = "episode_cap"
    time_out = True

    def check(self, ctx: StepContext) -> torch.Tensor:
        return ctx.episode_step >= self.config.max_steps


@retarget.hookimpl
def register_terminations(register) -> None:
    register(EpisodeCap)
