"""The fail penalty of App. A: a constant reward (-5) on the step an episode fails.

Failure is decided by the termination manager *after* rewards are computed from the step
context, so no term can see it in ``compute``. This term therefore contributes nothing there
(``compute`` returns zeros) and is marked ``on_failure = True``: the reward manager adds
``weight * penalty(failed)`` for the environments whose episode ended by a failure this step
(terminations that are not time-outs; an episode cap never triggers it).
"""

from __future__ import annotations

from typing import TYPE_CHECKING, ClassVar

from pydantic import Field

import retarget
from retarget import RewardConfig, RewardTerm, StepContext

if TYPE_CHECKING:
    import torch


class FailPenaltyConfig(RewardConfig):
    value: float = Field(-5.0, description="reward added on the step an episode fails")


class FailPenalty(RewardTerm):
    """Adds ``value`` (-5 for every character in Table 2) on the step an episode fails.

    Applied by the reward manager on failed environments through ``penalty(failed)``;
    ``compute`` is zero because failure is not known when terms are computed.
    """

    name = "fail_penalty"
    Config = FailPenaltyConfig
    on_failure: ClassVar[bool] = True
    """Tells the reward manager to call :meth:`penalty` with the failure mask of the step."""

    def compute(self, ctx: StepContext) -> torch.Tensor:
        import torch
        return torch.zeros(ctx.num_envs, dtype=torch.float32)

    def penalty(self, failed: torch.Tensor) -> torch.Tensor:
        """Unweighted ``(N,)`` penalty: ``value`` where ``failed`` (bool (N,)), else 0."""
        return failed.float() * self.config.value


@retarget.hookimpl
def register_rewards(register) -> None:
    register(FailPenalty)
