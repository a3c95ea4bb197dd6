"""Sensors (what the headset gives) and observers (what the policy perceives of the scene)."""

from __future__ import annotations

from abc import abstractmethod
from dataclasses import dataclass
from typing import TYPE_CHECKING, ClassVar

from retarget.kinds.step import StepPlugin

if TYPE_CHECKING:
    import torch

    from retarget.kinds.state import Layout, StepContext


@dataclass(frozen=True)
class ObsSpec:
    """Shape (without the leading ``N``) and dtype of one observation.

    The dtype is a torch dtype's name (``"float32"``), so declaring a spec needs no torch.
    """

    shape: tuple[int, ...]
    dtype: str = "float32"

    @property
    def torch_dtype(self) -> torch.dtype:
        import torch

        return getattr(torch, self.dtype)

    @property
    def size(self) -> int:
        n = 1
        for s in self.shape:
            n *= s
        return n


class Sensor(StepPlugin):
    """Base class of sensors: batched device signals in the character's heading frame.

    ``bind`` resolves names to indices once; ``observe`` returns ``(N, *spec.shape)`` for the
    environments in ``ctx`` and must not loop over environments.
    """

    kind: ClassVar[str] = "sensor"

    @abstractmethod
    def spec(self, layout: Layout) -> ObsSpec: ...

    @abstractmethod
    def observe(self, ctx: StepContext) -> torch.Tensor: ...

    def frames_needed(self) -> tuple[int, int]:
        """(past, future) reference frames this sensor reads from ``ctx.ref.devices``.

        The environment gathers the union of all sensors' windows once per step.
        """
        return (0, 0)


class Observer(Sensor):
    """Base class of observers: scene perception (height maps, point clouds), batched."""

    kind: ClassVar[str] = "observer"
