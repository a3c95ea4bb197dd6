"""The fail penalty of App. A: a constant reward (-5) on the step an episode fails.

Terminations are checked before rewards, and the step context says which environments failed
(``ctx.terminated``: failures only; time-outs such as an episode cap never trigger it).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from pydantic import Field

import retarget
from retarget import RewardConfig, RewardTerm, StepContext

if TYPE_CHECKING:
    import torch


class FailPenaltyConfig(RewardConfig):
    value: float = Field(-5.0, description="reward added on the step an episode fails")


class FailPenalty(RewardTerm[FailPenaltyConfig]):
    """Adds ``value`` (-5 for every character in Table 2) on the step an episode fails.

    ``value`` where ``ctx.terminated`` (the step's failures), else 0.
    """

    name = "fail_penalty"

    def compute(self, ctx: StepContext) -> torch.Tensor:
        import torch

        if ctx.terminated is None:  # outside a step (nothing has failed yet)
            return torch.zeros(ctx.num_envs, dtype=torch.float32)
        return ctx.terminated.float() * self.config.value


@retarget.hookimpl
def register_rewards(register) -> None:
    register(FailPenalty)
