"""Action regularisers of App. A: smooth (``action_diff``) and small (``action_min``) actions.

Both use the Gaussian kernel on a squared norm, so a still, smooth policy earns the full weight.
"""

from __future__ import annotations

import torch
from pydantic import Field

import retarget
from retarget import RewardConfig, RewardTerm, StepContext, gaussian_kernel


class ActionDiffConfig(RewardConfig):
    weight: float = 0.1
    k: float = Field(0.5, gt=0, description="kernel sensitivity on ||a_t - a_{t-1}||^2")


class ActionDiff(RewardTerm):
    """Rewards smooth control: exp(-k * ||a_t - a_{t-1}||^2)."""

    name = "action_diff"
    Config = ActionDiffConfig

    def compute(self, ctx: StepContext) -> torch.Tensor:
        d = (ctx.action - ctx.prev_action).square().sum(dim=-1)
        return gaussian_kernel(d, self.config.k).float()


class ActionMinConfig(RewardConfig):
    weight: float = 0.1
    k: float = Field(0.1, gt=0, description="kernel sensitivity on ||a_t||^2")


class ActionMin(RewardTerm):
    """Rewards small torques: exp(-k * ||a_t||^2)."""

    name = "action_min"
    Config = ActionMinConfig

    def compute(self, ctx: StepContext) -> torch.Tensor:
        d = ctx.action.square().sum(dim=-1)
        return gaussian_kernel(d, self.config.k).float()


@retarget.hookimpl
def register_rewards(register) -> None:
    register(ActionDiff)
    register(ActionMin)
