"""Terminations: which environments end this step, and whether that is a failure or a time-out."""

from __future__ import annotations

from abc import abstractmethod
from typing import TYPE_CHECKING, ClassVar

from retarget.kinds.base import ConfigT
from retarget.kinds.step import StepPlugin

if TYPE_CHECKING:
    import torch

    from retarget.kinds.state import StepContext


class Termination(StepPlugin[ConfigT]):
    """Base class of terminations.

    ``check`` returns a bool ``(N,)`` tensor; terminations run before rewards each step.
    ``time_out`` terms (episode caps) are truncations: PPO bootstraps their value instead of
    treating them as failures.
    """

    kind: ClassVar[str] = "termination"
    time_out: ClassVar[bool] = False

    @abstractmethod
    def check(self, ctx: StepContext) -> torch.Tensor: ...
