"""One live avatar: device samples in, sensors -> policy -> physics, the body out.

The run's environment is built for one environment over a standing idle clip just long enough
for the sensors' window; the reference frame stays there and each step writes the window of
the newest device poses into those library rows, computes the policy's observation
(:meth:`RetargetEnv.observe_now`), acts and steps only the physics
(:meth:`RetargetEnv.step_physics`: no rewards or training reference). So a session
runs for as long as the user streams, with no clip to run out of. Untracked devices hold
their last pose, as a headset runtime reports them.
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np
import torch

from retarget.errors import RetargetError
from retarget.kinds.capabilities import Acting, Exportable, require
from retarget.live.calibration import Calibration
from retarget.motion.device_recording import convert


@dataclass
class Latest:
    """The newest sample, already in the retarget convention (room frame)."""

    t: float
    poses: np.ndarray  # (3, 7)
    tracked: np.ndarray  # (3,)
    arrived: float  # perf_counter seconds
    images: np.ndarray | None = None  # (C, H, W) uint8


class LiveSession:
    """Steps a loaded run from device samples (``push``) one control step at a time."""

    def __init__(self, loaded) -> None:
        env = loaded.env
        group = require(loaded.algorithm, Exportable, hint="serve drives a character with a "
                        "policy").policy()[0]  # fmt: skip
        reads = {name for name, _ in env.obs_shapes.get(group, ())}
        for sensor in (s for s in env.sensors if s.name in reads):
            if sensor.needs().reference_offsets or sensor.name in ("full_body", "reference_action"):
                raise RetargetError(
                    f"the run's sensor '{sensor.name}' reads the reference body, which a live "
                    "stream does not have", hint="serve a student (hmd, three_point sensors)",
                )  # fmt: skip
            if sensor.recorded not in (None, "images"):
                raise RetargetError(
                    f"the run's sensor '{sensor.name}' reads a recorded {sensor.recorded!r} "
                    "stream, which is not sent live"
                )
        self.image_sensors = [s for s in env.sensors if s.name in reads and s.recorded]
        if env.num_envs != 1:
            raise RetargetError("a live session drives one environment")
        acting = require(loaded.algorithm, Acting, hint="serve drives a character with a policy")
        self.env, self.act, self.group = env, acting.act, group
        lib = env.library
        self.offsets = np.asarray(env.window_offsets)
        if self.offsets.max() > 0:
            raise RetargetError("the run's sensors read future device frames (future > 0), "
                                "which a live stream cannot give")  # fmt: skip
        self.frame0 = int(-self.offsets.min())  # the pinned reference frame
        self.rows = lib.rows(torch.zeros(1, dtype=torch.long),
                             torch.tensor([self.frame0]), tuple(env.window_offsets))[0]  # fmt: skip
        start = lib.devices[self.rows[-1]].double().numpy()  # (3, 7) at the pinned frame
        self.start_headset = start[0]
        self.scaled = env.options.devices == "character"  # devices at the character's size
        # standing history, one frame behind: each step shifts it and appends the newest
        before = lib.rows(torch.zeros(1, dtype=torch.long), torch.tensor([self.frame0 - 1]),
                          tuple(env.window_offsets))[0]  # fmt: skip
        self.window = lib.devices[before].double().numpy()  # world, oldest first
        self.window_tracked = np.ones(self.window.shape[:2], dtype=bool)  # (W, 3)
        env.place(torch.zeros(1, dtype=torch.long), torch.tensor([self.frame0]))
        self.held = start.copy()  # room frame after calibration; world before the first sample
        self.calibration: Calibration | None = None
        self.latest: Latest | None = None
        self.used: Latest | None = None
        self.steps = 0
        self.bodies = tuple(env.layout.body_names)
        self.images: np.ndarray | None = None  # the latest camera frames, held until new ones
        self.rig: str | None = None

    def push(self, t: float, poses: np.ndarray, tracked: np.ndarray, convention: str,
             images: np.ndarray | None = None, rig: str | None = None) -> None:  # fmt: skip
        """A new sample (the latest wins); poses in ``convention``, the client's room;
        ``images`` ``(C, H, W)`` for an image student, from the cameras ``rig`` (JSON)."""
        if images is not None:
            self.images, self.rig = images, rig
        here = convert(poses, convention, "retarget")
        if self.calibration is None:
            if not tracked[0]:
                return  # calibrate on the first sample that has the headset
            self.calibration = Calibration.between(here[0], self.start_headset,
                                                   scale=self.scaled)  # fmt: skip
            self.held = here.copy()
        self.held = np.where(tracked[:, None], here, self.held)
        self.latest = Latest(t, self.held.copy(), tracked.copy(), time.perf_counter(), images)

    def step(self) -> dict:
        """One control step with the newest sample; the body in the world frame."""
        env, lib = self.env, self.env.library
        self.used = self.latest
        if self.latest is not None and self.calibration is not None:
            # the mapping a recording gets (align_to: move_poses), so live equals play --input
            current = self.calibration.to_world(self.latest.poses)
            tracked = self.latest.tracked
        else:
            current, tracked = self.window[-1], self.window_tracked[-1]
        self.window = np.concatenate([self.window[1:], current[None]], axis=0)
        self.window_tracked = np.concatenate([self.window_tracked[1:], tracked[None]], axis=0)
        lib.devices[self.rows] = torch.as_tensor(self.window, dtype=lib.devices.dtype)
        lib.devices_tracked[self.rows] = torch.as_tensor(self.window_tracked)
        if self.image_sensors:
            self._replay_images()
        with torch.no_grad():
            obs = env.observe_now([self.group])
            env.step_physics(self.act(obs))
        self.steps += 1
        s = env.sim.state
        return {
            "root": s.qpos[0, :7].double().numpy(),
            "body_pos": s.body_pos[0].double().numpy(),
            "body_quat": s.body_quat[0].double().numpy(),
        }

    def _replay_images(self) -> None:
        """The latest camera frames into the image sensors' row of the pinned frame (held
        until newer ones arrive, like the devices)."""
        from pathlib import Path

        from retarget import RecordedStream

        if self.images is None:
            return  # until frames arrive the sensors show the standing body's rendered views
        row = self.rows[-1:]
        stream = RecordedStream(self.images[None], {"rig": self.rig or ""}, Path("live stream"))
        for sensor in self.image_sensors:
            sensor.replay(row, stream)

    def in_room(self, pose: dict, convention: str) -> dict:
        """A step's body moved back into the user's room, in ``convention``."""
        poses = np.concatenate([pose["body_pos"], pose["body_quat"]], axis=-1)
        root = pose["root"][None]
        if self.calibration is not None:
            poses, root = self.calibration.to_room(poses), self.calibration.to_room(root)
        poses, root = convert(poses, "retarget", convention), convert(root, "retarget", convention)
        return {"root": root[0], "body_pos": poses[:, :3], "body_quat": poses[:, 3:]}
