"""Terminations: which environments end this step, and whether that is a failure or a time-out."""

from __future__ import annotations

from abc import abstractmethod
from typing import TYPE_CHECKING, ClassVar

from retarget.kinds.base import Plugin

if TYPE_CHECKING:
    import torch

    from retarget.kinds.state import Layout, StepContext


class Termination(Plugin):
    """Base class of terminations.

    ``check`` returns a bool ``(N,)`` tensor. ``time_out`` terms (episode caps) are truncations:
    PPO bootstraps their value instead of treating them as failures.
    """

    kind: ClassVar[str] = "termination"
    time_out: ClassVar[bool] = False

    def bind(self, layout: Layout) -> None:
        """Resolve names to indices once."""

    @abstractmethod
    def check(self, ctx: StepContext) -> torch.Tensor: ...

    def reset(self, env_ids: torch.Tensor) -> None:
        """Forget per-environment state of ``env_ids``."""
