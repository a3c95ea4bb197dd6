"""Sensors (what the headset gives) and observers (what the policy perceives of the scene)."""

from __future__ import annotations

from abc import abstractmethod
from dataclasses import dataclass
from typing import TYPE_CHECKING, ClassVar

from retarget.kinds.base import ConfigT
from retarget.kinds.step import StepPlugin

if TYPE_CHECKING:
    from collections.abc import Mapping
    from pathlib import Path

    import numpy as np
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


@dataclass(frozen=True)
class RecordedStream:
    """What a real headset recorded for a sensor, matched to library rows by time.

    ``values`` has one entry per row given to :meth:`Sensor.replay` (``(R, *spec.shape)``),
    ``meta`` the recording's description of the device (e.g. ``{"rig": JSON}`` for cameras)
    and ``source`` the file it came from, for error messages.
    """

    values: np.ndarray
    meta: Mapping[str, str]
    source: Path


class Sensor(StepPlugin[ConfigT]):
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

    def deployable(self) -> tuple[torch.nn.Module, int, dict] | None:
        """A sensor that runs a network (a pose estimator: a two-stage tracker's first stage)
        gives ``(module, input width, description)`` here, so ``retarget export`` writes it
        as its own ONNX file beside the policy's; ``None`` (most sensors): plain features."""
        return None

    recorded: ClassVar[str | None] = None
    """The stream of a device recording this sensor reads on a real headset instead of what
    it derives from the reference (``"images"``: camera frames); ``None`` (most sensors): it
    derives everything from the device poses, which a recording replaces by itself."""

    def replay(self, rows: torch.Tensor, stream: RecordedStream) -> None:
        """From now on, library ``rows`` read ``stream.values`` (one per row, as recorded)
        instead of what :meth:`prepare` derived; called by ``retarget play --input`` for
        sensors that declare :attr:`recorded`. Raise ``PluginError`` naming ``stream.source``
        when the recording does not fit (shape, device)."""
        from retarget.errors import PluginError

        raise PluginError(
            f"reads no recorded stream (recorded = {self.recorded!r})", plugin=self.name
        )


class Observer(Sensor[ConfigT]):
    """Base class of observers: scene perception (height maps, point clouds), batched."""

    kind: ClassVar[str] = "observer"
