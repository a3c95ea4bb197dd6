"""Action regularisers of App. A: smooth (``action_diff``) and small (``action_min``) actions.

Both use the Gaussian kernel on the *mean* squared action (Eq. 9 and 10 divide by the number of
actions), so a still, smooth policy earns the full weight and ``k`` means the same for a
16-joint and a 30-joint character.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from pydantic import Field

import retarget
from retarget import RewardConfig, RewardTerm, StepContext, gaussian_kernel

if TYPE_CHECKING:
    import torch


class ActionDiffConfig(RewardConfig):
    weight: float = 1.5
    k: float = Field(10.0, gt=0, description="kernel sensitivity on mean((a_t - a_{t-1})^2)")


class ActionDiff(RewardTerm[ActionDiffConfig]):
    """Rewards smooth control: exp(-k * mean((a_t - a_{t-1})^2)).

    Table 2: Jesse (the default) w=1.5, k=10; Oppy and Dino w=2, k=150.
    """

    name = "action_diff"

    def compute(self, ctx: StepContext) -> torch.Tensor:
        d = (ctx.action - ctx.prev_action).square().mean(dim=-1)
        return gaussian_kernel(d, self.config.k).float()


class ActionMinConfig(RewardConfig):
    weight: float = 0.5
    k: float = Field(25.0, gt=0, description="kernel sensitivity on mean(a_t^2)")


class ActionMin(RewardTerm[ActionMinConfig]):
    """Rewards small torques: exp(-k * mean(a_t^2)).

    Table 2: Jesse (the default) w=0.5, k=25; Oppy and Dino w=0.2, k=25.
    """

    name = "action_min"

    def compute(self, ctx: StepContext) -> torch.Tensor:
        d = ctx.action.square().mean(dim=-1)
        return gaussian_kernel(d, self.config.k).float()


@retarget.hookimpl
def register_rewards(register) -> None:
    register(ActionDiff)
    register(ActionMin)
