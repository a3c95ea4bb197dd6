"""Headset and controller sensors: what a VR user's devices report, as the policy sees it.

The reference carries device poses over a time window (``ref.devices`` ``(N, W, D, 7)``:
headset, left, right controller; position + ``wxyz``; ``ref.window_offsets`` the frame offset of
each of the W entries, 0 being now). A sensor picks the frames ``-past .. +future`` from it and
expresses them in the *simulated* character's heading frame (:mod:`retarget.geometry.heading`):
rotated by the inverse of the root's yaw and moved to the root's ground projection, heights kept as
world heights. Orientations are given as 6D rotations. The layout of one observation is
frame-major: for each frame (oldest first), each device's position then its 6D rotation.

Future frames exist only offline; a policy meant to run live uses ``future: 0`` (QuestEnvSim
reports the loss of 1 s of future as a moderate drop in success rate).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from pydantic import Field
from typing_extensions import TypeVar

import retarget
from retarget import Layout, ObsSpec, PluginConfig, PluginError, Sensor, StepContext

if TYPE_CHECKING:
    import torch

DEVICES = ("headset", "left", "right")
"""Device order along the ``D`` axis of ``ref.devices``."""


class DeviceWindowConfig(PluginConfig):
    past: int = Field(
        1,
        ge=0,
        description="past frames before the current one; the paper's Eq. 2 gives two "
        "consecutive readings (past 1) so that the policy can infer the user's velocity",
    )
    future: int = Field(0, ge=0, description="future frames after the current one (offline only)")


class HmdConfig(DeviceWindowConfig):
    keep_height: bool = Field(
        True, description="positions keep world height; false makes them relative to the root"
    )


class ThreePointConfig(HmdConfig):
    controller_rotation: bool = Field(
        True, description="include controller orientations; false = positions only (QuestEnvSim)"
    )


DeviceConfigT = TypeVar("DeviceConfigT", bound=DeviceWindowConfig, default=DeviceWindowConfig)
PoseConfigT = TypeVar("PoseConfigT", bound=HmdConfig, default=HmdConfig)


class _DeviceWindow(Sensor[DeviceConfigT]):
    """Selection of the frames ``-past .. future`` from the reference's device window."""

    def __init__(self, config: PluginConfig | None = None) -> None:
        super().__init__(config)
        self._window_cache: tuple[tuple[int, ...], slice | torch.Tensor] | None = None

    def frames_needed(self) -> tuple[int, int]:
        return (self.config.past, self.config.future)

    @property
    def frames(self) -> int:
        return self.config.past + 1 + self.config.future

    def _features_per_frame(self) -> int:
        raise NotImplementedError

    def spec(self, layout: Layout) -> ObsSpec:
        return ObsSpec((self.frames * self._features_per_frame(),))

    def _window(self, offsets: tuple[int, ...]) -> slice | torch.Tensor:
        """Entries of the W axis for offsets ``-past .. future`` (cached per offsets tuple).

        A slice when they are consecutive (the usual case: a view, no copy), else an index.
        """
        import torch
        if self._window_cache is not None and self._window_cache[0] == offsets:
            return self._window_cache[1]
        wanted = range(-self.config.past, self.config.future + 1)
        missing = [o for o in wanted if o not in offsets]
        if missing:
            raise PluginError(
                f"the reference window {list(offsets)} lacks frame offsets {missing} needed for "
                f"past={self.config.past}, future={self.config.future}",
                plugin=self.name,
                hint="widen the environment's device window or lower past/future",
            )
        found = [offsets.index(o) for o in wanted]
        if found == list(range(found[0], found[0] + len(found))):
            idx: slice | torch.Tensor = slice(found[0], found[0] + len(found))
        else:
            idx = torch.tensor(found, dtype=torch.long)
        self._window_cache = (offsets, idx)
        return idx


class _DeviceSensor(_DeviceWindow[PoseConfigT]):
    """Device poses in the simulated character's heading frame."""

    def _devices(self, ctx: StepContext, count: int) -> tuple[torch.Tensor, torch.Tensor]:
        """Positions ``(N, F, d, 3)`` and 6D rotations ``(N, F, d, 6)`` of the first ``count``
        devices in the heading frame (device quaternions are unit, as ``ReferenceBatch`` says).
        """
        import torch

        from retarget.geometry.heading import ground_origin, heading_cos_sin, quat_to_6d, unyaw
        if ctx.ref.devices.shape[2] < count:
            raise PluginError(
                f"needs {count} devices (headset, left, right) but the reference has "
                f"{ctx.ref.devices.shape[2]}",
                plugin=self.name,
            )
        window = self._window(tuple(ctx.ref.window_offsets))
        dev = ctx.ref.devices[:, window, :count]  # (N, F, d, 7)
        root_pos, root_quat = ctx.sim.qpos[:, :3], ctx.sim.qpos[:, 3:7]
        origin = ground_origin(root_pos, self.config.keep_height)
        rel = dev[..., :3] - origin[:, None, None]
        cols = quat_to_6d(dev[..., 3:7]).unflatten(-1, (2, 3))
        # one yaw rotation for positions and both rotation columns: (N, F, d, 3 vectors, 3)
        vectors = unyaw(torch.cat([rel.unsqueeze(-2), cols], dim=-2), *heading_cos_sin(root_quat))
        return vectors[..., 0, :], vectors[..., 1:, :].flatten(-2)


class Hmd(_DeviceSensor[HmdConfig]):
    """Headset only: position (3) and 6D orientation (6) per frame, in the heading frame.

    The 1-point setting of QuestEnvSim: enough for plausible whole-body motion, with the arms
    left to the policy.
    """

    name = "hmd"
    requires = ("site:head",)

    def _features_per_frame(self) -> int:
        return 9

    def observe(self, ctx: StepContext) -> torch.Tensor:
        import torch
        pos, rot = self._devices(ctx, 1)
        return torch.cat([pos, rot], dim=-1).reshape(ctx.num_envs, -1).float()


class ThreePoint(_DeviceSensor[ThreePointConfig]):
    """Headset pose and both controllers, per frame, in the character's heading frame.

    Per frame: headset position (3) + 6D orientation (6), then left and right controller
    position (3 each) + 6D orientation (6 each) when ``controller_rotation`` (27 values), or
    positions only (15 values), QuestEnvSim's choice since controller orientation depends on how
    a user holds them.
    """

    name = "three_point"
    requires = ("site:head", "site:left_hand", "site:right_hand")

    def _features_per_frame(self) -> int:
        return 27 if self.config.controller_rotation else 15

    def observe(self, ctx: StepContext) -> torch.Tensor:
        import torch
        pos, rot = self._devices(ctx, 3)
        if self.config.controller_rotation:
            per_device = torch.cat([pos, rot], dim=-1)  # (N, F, 3, 9)
        else:
            hmd = torch.cat([pos[:, :, :1], rot[:, :, :1]], dim=-1).flatten(2)  # (N, F, 9)
            per_device = torch.cat([hmd, pos[:, :, 1:].flatten(2)], dim=-1)  # (N, F, 15)
        return per_device.reshape(ctx.num_envs, -1).float()


class ControllerTracking(_DeviceWindow[DeviceWindowConfig]):
    """Whether each controller is tracked, per frame: left then right, 1 tracked, 0 lost (its
    last pose held in ``three_point``), as headset runtimes report it.

    Beside ``three_point``: without it a held controller looks like a still hand, so a policy
    trained with controllers that lose tracking (``env.device_noise.lost``) learns to doubt
    every still one. Its own source, so a three-point policy
    started from one without it (``--init-from``) keeps its device weights and learns these
    from zero."""

    name = "controller_tracking"
    requires = ("site:left_hand", "site:right_hand")

    def _features_per_frame(self) -> int:
        return 2

    def observe(self, ctx: StepContext) -> torch.Tensor:
        tracked = ctx.ref.tracked()[:, self._window(tuple(ctx.ref.window_offsets)), 1:3]
        return tracked.reshape(ctx.num_envs, -1).float()


@retarget.hookimpl
def register_sensors(register) -> None:
    register(Hmd)
    register(ThreePoint)
    register(ControllerTracking)
