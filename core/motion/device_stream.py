"""Driving a policy from a recorded device stream instead of motion capture.

A recording (:mod:`retarget.motion.device_recording`) has its own clock and its own room
origin. To drive an environment it is resampled to the control rate (positions linearly,
rotations by slerp; untracked samples hold the last tracked pose, as a headset runtime does)
and calibrated like a VR application calibrates its avatar: translated and turned about the
vertical so that the first headset pose stands where the character starts, and, for a run whose
devices are at the character's scale (``env.devices: character``), scaled by the ratio of the
character's standing headset height to the user's first one (the user stands at the start).
"""

from __future__ import annotations

import numpy as np

from retarget.geometry import rotations as rot
from retarget.motion.device_recording import DeviceRecording


def hold_untracked(rec: DeviceRecording) -> np.ndarray:
    """Poses ``(T, 3, 7)`` where untracked samples repeat the device's previous tracked pose
    (before the first tracked one: its first tracked pose)."""
    poses = rec.poses.copy()
    for d in range(poses.shape[1]):
        tracked = np.flatnonzero(rec.tracked[:, d])
        if tracked.size == 0:
            continue
        idx = np.maximum.accumulate(np.where(rec.tracked[:, d], np.arange(len(poses)), -1))
        idx = np.where(idx < 0, tracked[0], idx)
        poses[:, d] = rec.poses[idx, d]
    return poses


def _sample_at(rec: DeviceRecording, hz: float) -> tuple[np.ndarray, np.ndarray]:
    """For each control frame from the first sample to the last: the sample at or before it
    and the one after it (the last sample twice at the end)."""
    t = rec.time - rec.time[0]
    frames = int(np.floor(t[-1] * hz + 1e-9)) + 1
    query = np.arange(frames) / hz
    k = np.clip(np.searchsorted(t, query, side="right") - 1, 0, len(t) - 1)
    return k, np.minimum(k + 1, len(t) - 1)


def resample_tracked(rec: DeviceRecording, hz: float) -> np.ndarray:
    """Whether each device is tracked at each control frame of :func:`resample_stream`:
    ``(F, 3)`` bool, the state of the sample at or before the frame (a pose between a tracked
    sample and a lost one is the held pose, as the runtime reports it)."""
    k, _ = _sample_at(rec, hz)
    return rec.tracked[k].astype(bool)


def resample_stream(rec: DeviceRecording, hz: float) -> np.ndarray:
    """The stream at ``hz`` from its first to its last sample: ``(F, 3, 7)``."""
    poses = hold_untracked(rec)
    t = rec.time - rec.time[0]
    k, k1 = _sample_at(rec, hz)
    query = np.arange(len(k)) / hz
    span = np.where(k1 > k, t[k1] - t[k], 1.0)
    w = np.clip((query - t[k]) / span, 0.0, 1.0)[:, None, None]
    pos = poses[k, :, :3] * (1 - w) + poses[k1, :, :3] * w
    quat = rot.slerp(poses[k, :, 3:], poses[k1, :, 3:], w)
    return np.concatenate([pos, quat], axis=-1)


MIN_HEADSET, MAX_SCALE = 0.3, 4.0
"""A first headset pose below 0.3 m, or a scale beyond 1/4..4, is not a standing user."""


def height_scale(first_hmd: np.ndarray, hmd: np.ndarray) -> float:
    """How much larger than the user the character's reference is: the height of ``hmd`` (the
    character's standing headset) over that of the user's first headset pose ``first_hmd``."""
    user, own = float(first_hmd[2]), float(hmd[2])
    scale = own / user if user > MIN_HEADSET else float("nan")
    if not 1.0 / MAX_SCALE <= scale <= MAX_SCALE:
        raise ValueError(
            f"the first headset pose is {user:.2f} m above the floor, the character's standing "
            f"headset {own:.2f} m: calibrating the avatar's size needs the user standing at the "
            "start (headset heights in metres, z or y up as the convention says)"
        )
    return scale


def align_to(poses: np.ndarray, hmd: np.ndarray, *, scale: bool = False) -> np.ndarray:
    """Move the stream rigidly (vertical-axis rotation + horizontal translation) so that its
    first headset pose has the horizontal position and heading of ``hmd`` (7,). Heights are
    kept (the user's real heights above the floor) unless ``scale``: then every position is
    also scaled about the floor under that first pose by :func:`height_scale`, so that the
    first headset is at ``hmd``'s height and a step of the user is a step of the character."""
    yaw = float(rot.yaw(hmd[3:]) - rot.yaw(poses[0, 0, 3:]))
    k = height_scale(poses[0, 0], hmd) if scale else 1.0
    return move_poses(poses, yaw, poses[0, 0, :2], hmd[:2], k)


def move_poses(
    poses: np.ndarray, yaw: float, origin: np.ndarray, target: np.ndarray, scale: float = 1.0
) -> np.ndarray:
    """Turn poses ``(..., 7)`` by ``yaw`` about +Z around ``origin`` (xy), scale positions by
    ``scale`` about the floor under it and put ``origin`` at ``target``: the one room-to-world
    mapping of a recording (:func:`align_to`) and of a live session
    (:class:`retarget.live.calibration.Calibration`, both ways)."""
    c, s = np.cos(yaw), np.sin(yaw)
    m = np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])
    q = rot.from_axis_angle(np.array([0.0, 0.0, 1.0]), np.array(yaw))
    pos = poses[..., :3].copy()
    pos[..., :2] -= origin
    pos = pos @ m.T * scale
    pos[..., :2] += target
    quat = rot.mul(np.broadcast_to(q, poses[..., 3:].shape), poses[..., 3:])
    return np.concatenate([pos, rot.normalize(quat)], axis=-1)
