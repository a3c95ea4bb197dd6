"""Reward terms: unweighted ``(N,)`` values; the reward manager applies weights and logs."""

from __future__ import annotations

from abc import abstractmethod
from typing import TYPE_CHECKING, ClassVar

from pydantic import Field
from typing_extensions import TypeVar

from retarget.kinds.base import PluginConfig
from retarget.kinds.step import StepPlugin

if TYPE_CHECKING:
    import torch

    from retarget.kinds.state import StepContext


def gaussian_kernel(distance: torch.Tensor, k: float) -> torch.Tensor:
    """The paper's ``exp(-k * d)`` kernel (the weight ``w`` is applied by the manager)."""
    import torch
    return torch.exp(-k * distance)


class RewardConfig(PluginConfig):
    """Fields shared by every reward term."""

    weight: float = Field(1.0, description="w in w*exp(-k*d); 0 disables the term")


RewardConfigT = TypeVar("RewardConfigT", bound=RewardConfig, default=RewardConfig)


class RewardTerm(StepPlugin[RewardConfigT]):
    """Base class of reward terms.

    ``compute`` returns an unweighted float32 ``(N,)`` tensor; the manager multiplies by
    ``config.weight``, skips zero weights and logs per-term episode sums. Terminations are
    checked first, so a term paid on failure reads ``ctx.terminated``.
    """

    kind: ClassVar[str] = "reward"
    Config: ClassVar[type[PluginConfig]] = RewardConfig

    @abstractmethod
    def compute(self, ctx: StepContext) -> torch.Tensor: ...
