"""Synthesised VR device poses (headset, left and right controller) from human motion.

Training has no headset: the devices are derived from the mocap body through fixed mounts.
Device poses are ``(..., 3, 7)``: devices in the order :data:`DEVICES`, each position (metres,
world Z up) + orientation (wxyz). A device frame follows the canonical convention: +X is where
it points (the headset's view direction, a controller's pointing direction), +Z is up.

Mounts (for a 1.75 m adult, scaled with the subject's height), in the parent joint's frame:

* headset: on the ``head`` joint (skull base), 0.09 m forward and 0.08 m up (between the
  eyes), same orientation as the head (looks along the head's +X);
* controllers: on the ``left_wrist``/``right_wrist`` joints, 0.08 m along the hand (+Y for the
  left hand, -Y for the right in the T-pose) and 0.02 m towards the palm (-Z), same
  orientation as the wrist: in the T-pose (arms sideways, palms down, fists closed round the
  grip) a controller points forward, +X.

Augmentations model real tracking: Gaussian position/rotation noise, a latency of whole frames
(the device reports the pose of ``latency`` frames ago) and dropout (with probability ``p`` per
frame and device the tracker loses the device and repeats its last reported pose).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from retarget.geometry import rotations as rot
from retarget.motion import skeleton as sk

DEVICES: tuple[str, str, str] = ("hmd", "left", "right")
MOUNT_JOINTS: tuple[int, int, int] = (
    sk.joint_index("head"),
    sk.joint_index("left_wrist"),
    sk.joint_index("right_wrist"),
)
MOUNT_OFFSETS_175 = np.array([[0.09, 0.0, 0.08], [0.0, 0.08, -0.02], [0.0, -0.08, -0.02]])
MOUNT_ROTATIONS = rot.identity((3,))


def mount_offsets(height: float = sk.REFERENCE_HEIGHT) -> np.ndarray:
    """Device mount offsets ``(3, 3)`` in their joints' frames for a subject of ``height``."""
    return MOUNT_OFFSETS_175 * (height / sk.REFERENCE_HEIGHT)


def device_poses(
    global_pos: np.ndarray, global_rot: np.ndarray, height: float = sk.REFERENCE_HEIGHT
) -> np.ndarray:
    """Device poses ``(..., 3, 7)`` from joint positions ``(..., J, 3)`` and rotations."""
    joints = np.array(MOUNT_JOINTS)
    jrot = global_rot[..., joints, :]
    pos = global_pos[..., joints, :] + rot.apply(jrot, mount_offsets(height))
    quat = rot.normalize(rot.mul(jrot, MOUNT_ROTATIONS))
    return np.concatenate([pos, quat], axis=-1)


@dataclass(frozen=True)
class DeviceNoise:
    """Tracking imperfections to augment synthesised devices with (all off by default)."""

    position_std: float = 0.0  # metres
    rotation_std: float = 0.0  # radians, about a random axis
    latency: int = 0  # frames
    dropout: float = 0.0  # probability per frame and device


def perturb(
    poses: np.ndarray, noise: DeviceNoise, rng: np.random.Generator, *, time_axis: int = 0
) -> tuple[np.ndarray, np.ndarray]:
    """Apply ``noise`` to device poses ``(..., T, ..., 3, 7)``; returns (poses, tracked mask).

    ``time_axis`` names the frame axis (latency and dropout hold values along it). Fully
    vectorised: dropout holds use a running maximum of the last tracked frame index.
    """
    out = np.array(poses, dtype=np.float64, copy=True)
    out = np.moveaxis(out, time_axis, 0)  # (T, ..., 3, 7)
    t = out.shape[0]
    if noise.latency > 0:
        idx = np.maximum(np.arange(t) - noise.latency, 0)
        out = out[idx]
    if noise.position_std > 0:
        out[..., :3] += rng.normal(0.0, noise.position_std, size=out[..., :3].shape)
    if noise.rotation_std > 0:
        axis = rng.normal(size=out[..., :3].shape)
        ang = rng.normal(0.0, noise.rotation_std, size=out.shape[:-1])
        out[..., 3:] = rot.normalize(rot.mul(rot.from_axis_angle(axis, ang), out[..., 3:]))
    tracked = np.ones(out.shape[:-1], dtype=bool)
    if noise.dropout > 0:
        tracked = rng.random(out.shape[:-1]) >= noise.dropout
        tracked[0] = True
        frame = np.arange(t).reshape((t,) + (1,) * (tracked.ndim - 1))
        last = np.maximum.accumulate(np.where(tracked, frame, 0), axis=0)
        out = np.take_along_axis(out, last[..., None], axis=0)
    return np.moveaxis(out, 0, time_axis), np.moveaxis(tracked, 0, time_axis)
