"""Device calibration noise: each training episode's devices sit a little higher or lower.

A policy trained on devices derived exactly from the reference learns the headset's height to
the centimetre; on a real headset the height never matches that well (the avatar's size is
calibrated once, from the user standing at the start, and no person walks at the same height
fraction as the clip's performer). A three-point student trained without noise falls on a
held-out walk whose devices are 2 cm higher than the reference's, and follows the same walk
with them exact. So, while a trainer turns it on, every episode draws one vertical offset
uniformly in ``[-height, height]`` and one height scale in ``[1 - scale, 1 + scale]`` (about
the floor) for all its devices and every frame of its device window; the student learns to
walk whatever they are. Only device poses change: the reference body, rewards and the teacher
do not see it, and evaluation, play, export and live sessions never do (``active`` is set by
a trainer each iteration and false everywhere else).

The draws come from their own generator, so turning the noise on leaves every other random
choice of a run (starts, scenes) as it was; offsets and generator are saved with the
environment's state, so a resumed run continues the same episodes.
"""

from __future__ import annotations

from collections.abc import Mapping

import torch

from retarget.settings.env import DeviceNoiseOptions


class DeviceNoise:
    """Per-environment offset and scale of device heights, redrawn at every reset."""

    def __init__(self, options: DeviceNoiseOptions, num_envs: int, seed: int) -> None:
        self.options = options
        self.active = False  # set by a trainer each iteration; false everywhere else
        self.generator = torch.Generator().manual_seed(seed + 7919)
        self.offset = torch.zeros(num_envs)
        self.scale = torch.ones(num_envs)
        self.redraw(torch.arange(num_envs))

    def redraw(self, env_ids: torch.Tensor) -> None:
        """New calibration errors for the episodes starting in ``env_ids``."""
        n = int(env_ids.numel())
        if n == 0:
            return
        u = torch.rand(2, n, generator=self.generator) * 2.0 - 1.0
        self.offset[env_ids] = u[0] * self.options.height
        self.scale[env_ids] = 1.0 + u[1] * self.options.scale

    def apply(self, devices: torch.Tensor) -> torch.Tensor:
        """``devices`` ``(N, W, D, 7)`` with heights moved (a copy); unchanged when inactive."""
        if not self.active:
            return devices
        out = devices.clone()
        z = out[..., 2]
        out[..., 2] = z * self.scale.to(z.dtype)[:, None, None] + self.offset.to(z.dtype)[
            :, None, None
        ]
        return out

    def state_dict(self) -> dict:
        return {
            "offset": self.offset.clone(),
            "scale": self.scale.clone(),
            "generator": self.generator.get_state(),
        }

    def load_state_dict(self, state: Mapping) -> None:
        if state["offset"].shape != self.offset.shape:
            raise ValueError(
                f"device noise for {state['offset'].shape[0]} environments, this env "
                f"{self.offset.shape[0]}"
            )
        self.offset = state["offset"].clone()
        self.scale = state["scale"].clone()
        self.generator.set_state(state["generator"])
