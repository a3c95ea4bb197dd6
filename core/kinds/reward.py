"""Reward terms: unweighted ``(N,)`` values; the reward manager applies weights and logs."""

from __future__ import annotations

from abc import abstractmethod
from typing import TYPE_CHECKING, ClassVar

from pydantic import Field

from retarget.kinds.base import Plugin, PluginConfig

if TYPE_CHECKING:
    import torch

    from retarget.kinds.state import Layout, StepContext


def gaussian_kernel(distance: torch.Tensor, k: float) -> torch.Tensor:
    """The paper's ``exp(-k * d)`` kernel (the weight ``w`` is applied by the manager)."""
    import torch
    return torch.exp(-k * distance)


class RewardConfig(PluginConfig):
    """Fields shared by every reward term."""

    weight: float = Field(1.0, description="w in w*exp(-k*d); 0 disables the term")


class RewardTerm(Plugin):
    """Base class of reward terms.

    ``compute`` returns an unweighted float32 ``(N,)`` tensor; the manager multiplies by
    ``config.weight``, skips zero weights and logs per-term episode sums.
    """

    kind: ClassVar[str] = "reward"
    Config: ClassVar[type[PluginConfig]] = RewardConfig
    on_failure: ClassVar[bool] = False
    """True for a term paid when an episode fails (``fail_penalty``): the manager then adds
    ``weight * penalty(failed)`` once the step's failures are known."""

    def bind(self, layout: Layout) -> None:
        """Resolve joint/body names and weights to index tensors once."""

    @abstractmethod
    def compute(self, ctx: StepContext) -> torch.Tensor: ...

    def reset(self, env_ids: torch.Tensor) -> None:
        """Forget per-environment state of ``env_ids`` (only stateful terms need this)."""

    def penalty(self, failed: torch.Tensor) -> torch.Tensor:
        """``(N,)`` unweighted value for the environments whose episode just failed (``failed``
        ``(N,)`` bool); used only when :attr:`on_failure` is true. Default: nothing."""
        import torch
        return torch.zeros(failed.shape[0])
