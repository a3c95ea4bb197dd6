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

With ``lost`` above 0, a controller also loses tracking now and then (a chance per second;
each loss lasts up to ``lost_seconds``): from the frame it is lost its pose is held, in every
entry of the device window from that frame on, as ``serve`` and ``play --input`` hold an
untracked device. A real stream loses a controller whenever it leaves the cameras' view; a
student never trained on that falls when the held controller drifts behind the walking body.

The draws come from their own generator, so turning the noise on leaves every other random
choice of a run (starts, scenes) as it was; offsets and generator are saved with the
environment's state, so a resumed run continues the same episodes.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence

import torch

from retarget.settings.env import DeviceNoiseOptions


class DeviceNoise:
    """Per-environment offset and scale of device heights, redrawn at every reset, and
    per-controller losses of tracking (the pose held), drawn once per frame."""

    CONTROLLERS = (1, 2)  # device order: headset, left, right; the headset is not lost

    def __init__(self, options: DeviceNoiseOptions, num_envs: int, seed: int,
                 control_dt: float = 1.0 / 30.0) -> None:  # fmt: skip
        self.options = options
        self.active = False  # set by a trainer each iteration; false everywhere else
        self.generator = torch.Generator().manual_seed(seed + 7919)
        self.offset = torch.zeros(num_envs)
        self.scale = torch.ones(num_envs)
        self.control_dt = control_dt
        # per environment and controller: the frame tracking was lost at and the last frame
        # it stays lost (-1: tracked)
        self.lost_from = torch.full((num_envs, len(self.CONTROLLERS)), -1, dtype=torch.long)
        self.lost_to = torch.full_like(self.lost_from, -1)
        # the frame each environment last drew at: a step that reads its devices twice (once
        # more after resets) draws once, so ``lost`` stays a chance per second
        self.drawn_at = torch.full((num_envs,), -1, dtype=torch.long)
        self.redraw(torch.arange(num_envs))

    def redraw(self, env_ids: torch.Tensor) -> None:
        """New calibration errors for the episodes starting in ``env_ids``."""
        n = int(env_ids.numel())
        if n == 0:
            return
        u = torch.rand(2, n, generator=self.generator) * 2.0 - 1.0
        self.offset[env_ids] = u[0] * self.options.height
        self.scale[env_ids] = 1.0 + u[1] * self.options.scale
        self.lost_from[env_ids] = -1
        self.lost_to[env_ids] = -1
        self.drawn_at[env_ids] = -1

    def hold(self, devices: torch.Tensor, tracked: torch.Tensor, frame: torch.Tensor,
             window: Sequence[int], pose_at: Callable[[torch.Tensor], torch.Tensor],
             ) -> tuple[torch.Tensor, torch.Tensor]:  # fmt: skip
        """``devices`` ``(N, W, D, 7)`` (window frames ``frame + window``) with lost controllers
        held at their pose of the frame they were lost, and their ``tracked`` ``(N, W, D)``
        flags false there (copies): a runtime reports a lost controller untracked while it
        holds its pose, so a policy that reads the flag learns when the held pose is not the
        hand's. ``pose_at(frames)`` gives the ``(N, D, 7)`` devices of each environment's clip
        at ``frames`` ``(N,)``. Both unchanged when inactive or ``lost`` is 0."""
        if not self.active or self.options.lost <= 0.0:
            return devices, tracked
        n, k = self.lost_from.shape
        frame = frame.long()
        ended = (self.lost_from >= 0) & ((frame[:, None] > self.lost_to)
                                         | (frame[:, None] < self.lost_from))  # fmt: skip
        self.lost_from[ended] = -1
        u = torch.rand(2, n, k, generator=self.generator)
        fresh = (frame != self.drawn_at)[:, None]
        self.drawn_at = frame.clone()
        start = fresh & (self.lost_from < 0) & (u[0] < self.options.lost * self.control_dt)
        length = (u[1] * self.options.lost_seconds / self.control_dt).long()
        frames = frame[:, None].expand(n, k)
        self.lost_from = torch.where(start, frames, self.lost_from)
        self.lost_to = torch.where(start, frames + length, self.lost_to)
        if not bool((self.lost_from >= 0).any()):
            return devices, tracked
        out, flags = devices.clone(), tracked.clone()
        at = frame[:, None] + torch.as_tensor(window, dtype=torch.long)[None, :]  # (N, W)
        for j, d in enumerate(self.CONTROLLERS):
            lost = self.lost_from[:, j]
            held = pose_at(lost.clamp(min=0))[:, d]  # (N, 7)
            mask = (lost[:, None] >= 0) & (at >= lost[:, None])  # (N, W)
            out[:, :, d] = torch.where(mask[..., None], held[:, None].to(out.dtype), out[:, :, d])
            flags[:, :, d] &= ~mask
        return out, flags

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
            "lost_from": self.lost_from.clone(),
            "lost_to": self.lost_to.clone(),
            "drawn_at": self.drawn_at.clone(),
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
        if "lost_from" in state:  # states saved before losses of tracking existed have none
            self.lost_from = state["lost_from"].clone()
            self.lost_to = state["lost_to"].clone()
            self.drawn_at = state["drawn_at"].clone()
        self.generator.set_state(state["generator"])
