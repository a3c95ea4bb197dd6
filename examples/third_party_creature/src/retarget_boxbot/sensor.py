"""``head_velocity``: the headset's velocity, from its last two readings.

A sensor reads the device window the environment gathers (``ctx.ref.devices``, ``(N, W, D,
7)``: headset, left, right; position then wxyz) and declares how much of it it needs with
``frames_needed()``: here one past frame. Batched over environments, no Python loop.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from pydantic import Field

import retarget

if TYPE_CHECKING:  # torch is imported by the env before any step; `retarget --help` stays light
    import torch


class HeadVelocityConfig(retarget.PluginConfig):
    scale: float = Field(1.0, gt=0.0, le=100.0, description="multiplies the velocity (m/s)")


class HeadVelocity(retarget.Sensor[HeadVelocityConfig]):
    """Headset linear velocity (m/s, world frame) from the current and previous reading."""

    name = "head_velocity"

    def spec(self, layout: retarget.Layout) -> retarget.ObsSpec:
        return retarget.ObsSpec((3,))

    def frames_needed(self) -> tuple[int, int]:
        return (1, 0)

    def observe(self, ctx: retarget.StepContext) -> torch.Tensor:
        offsets = ctx.ref.window_offsets
        now, before = offsets.index(0), offsets.index(-1)
        head = ctx.ref.devices[:, :, 0, :3]
        return ((head[:, now] - head[:, before]) / ctx.dt * self.config.scale).float()


@retarget.hookimpl
def register_sensors(register) -> None:
    register(HeadVelocity)
