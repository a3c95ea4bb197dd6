"""The headset's own cameras as a sensor (SimXR): grayscale views of the reference person.

SimXR trains its student on what the headset's tracking cameras see of the *reference* body
(the mocap person), not of the simulated character: the images are rendered once per library
frame (:mod:`retarget.render.ego_cache`, cached on disk by content) in :meth:`prepare`, and each
step only indexes them by ``ctx.ref.rows``. The body is often out of view, so a student reads
this beside the headset pose (``hmd``). Read-time augmentation varies brightness per view and
adds pixel noise from a fixed bank indexed by frame and step, so the same step gives the same
images whichever environments are computed together.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Literal

from pydantic import Field

import retarget
from retarget import (
    Layout,
    ObsSpec,
    PluginConfig,
    PluginError,
    RecordedStream,
    Sensor,
    StepContext,
)
from retarget.motion.camera_rigs import RIGS, CameraRig

if TYPE_CHECKING:
    import torch

    from retarget.motion.library import MotionLibrary

NOISE_BANK = 64
"""Distinct noise images cycled through at read time."""


class EgoCamerasConfig(PluginConfig):
    rig: Literal["quest2", "aria"] | CameraRig = Field(
        "quest2",
        description="a packaged rig by name, or {cameras: [{name, pos, yaw, pitch, "
        "fovy}, ...]} (headset frame: +X ahead, +Y left, +Z up; degrees)",
    )
    width: int = Field(40, ge=16, le=640, description="pixels per view")
    height: int = Field(30, ge=12, le=480, description="pixels per view")
    brightness: float = Field(0.2, ge=0, le=0.9, description="views scaled by 1 +- this")
    noise: float = Field(0.02, ge=0, le=0.5, description="std of pixel noise (0..1 scale)")
    seed: int = Field(0, ge=0, le=2**31 - 1, description="seed of the augmentation bank")


class EgoCameras(Sensor[EgoCamerasConfig]):
    """Grayscale views ``(C, H, W)`` in [0, 1] from the headset's cameras (SimXR's input).

    Rendered from the reference motion once per library frame and read back each step; the
    first run over new clips renders them (progress bar), later runs read the cache.
    """

    name = "ego_cameras"
    recorded = "images"

    def __init__(self, config: PluginConfig | None = None) -> None:
        super().__init__(config)
        cfg = self.config
        self.rig = RIGS[cfg.rig] if isinstance(cfg.rig, str) else cfg.rig
        self._images: torch.Tensor | None = None
        self._owned = False  # whether _images is this sensor's own copy (after a replay)

    def spec(self, layout: Layout) -> ObsSpec:
        cfg = self.config
        return ObsSpec((len(self.rig.cameras), cfg.height, cfg.width))

    def prepare(self, library: MotionLibrary) -> None:
        import warnings

        import numpy as np
        import torch

        from retarget.render.ego_cache import ego_images

        cfg = self.config
        heights = np.repeat(library.heights.numpy(), library.length.numpy())
        images = ego_images(
            library.global_pos.numpy(), library.devices[:, 0].numpy(), heights, self.rig,
            cfg.width, cfg.height,
        )  # fmt: skip
        with warnings.catch_warnings():  # read-only memory map: indexed, never written
            warnings.simplefilter("ignore", UserWarning)
            self._images = torch.from_numpy(images)  # (R, C, H, W) uint8, shared pages
        self._owned = False
        g = torch.Generator().manual_seed(cfg.seed)
        shape = (NOISE_BANK, len(self.rig.cameras), cfg.height, cfg.width)
        self._noise = torch.randn(shape, generator=g) * cfg.noise
        self._gain = 1 + (torch.rand(NOISE_BANK, len(self.rig.cameras), 1, 1, generator=g) * 2
                          - 1) * cfg.brightness  # fmt: skip

    def replay(self, rows: torch.Tensor, stream: RecordedStream) -> None:
        """Recorded frames for ``rows``; real frames carry their own noise, so read-time
        augmentation is switched off from here on."""
        import numpy as np
        import torch
        from pydantic import ValidationError

        from retarget.motion.camera_rigs import CameraRig

        if self._images is None:
            raise PluginError("replay before prepare(library)", plugin=self.name)
        shape = (len(rows), *self._images.shape[1:])
        if stream.values.shape != shape or stream.values.dtype != np.uint8:
            raise PluginError(
                f"{stream.source}: frames are {stream.values.dtype} "
                f"{'x'.join(map(str, stream.values.shape[1:]))} but this sensor reads uint8 "
                f"{'x'.join(map(str, shape[1:]))} (cameras x height x width)", plugin=self.name,
            )  # fmt: skip
        try:
            rig = CameraRig.model_validate_json(stream.meta.get("rig", ""))
        except ValidationError:
            raise PluginError(
                f"{stream.source}: the frames name no valid camera rig", plugin=self.name
            ) from None
        if rig != self.rig:
            raise PluginError(
                f"{stream.source}: recorded with other cameras "
                f"({', '.join(c.name for c in rig.cameras)}) than this sensor's rig "
                f"({', '.join(c.name for c in self.rig.cameras)}, or other poses)",
                plugin=self.name,
            )
        if not self._owned:  # the memory map is read-only and shared: copy it once
            self._images, self._owned = self._images.clone(), True
            self._noise = torch.zeros_like(self._noise)
            self._gain = torch.ones_like(self._gain)
        self._images[rows] = torch.from_numpy(np.ascontiguousarray(stream.values))

    def observe(self, ctx: StepContext) -> torch.Tensor:
        if self._images is None or ctx.ref.rows is None:
            raise PluginError(
                "no camera images: prepare(library) was not called, or the step context has "
                "no reference rows", plugin=self.name,
            )  # fmt: skip
        rows = ctx.ref.rows.clamp(0, self._images.shape[0] - 1)
        views = self._images[rows].float() / 255.0
        pick = (rows * 7919 + ctx.episode_step * 104729) % NOISE_BANK  # per frame and step
        return (views * self._gain[pick] + self._noise[pick]).clamp(0.0, 1.0)


@retarget.hookimpl
def register_sensors(register) -> None:
    register(EgoCameras)
