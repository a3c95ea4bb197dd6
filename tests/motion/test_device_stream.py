"""Recorded device streams at the control rate: resampling, untracked samples, calibration."""

from __future__ import annotations

import numpy as np
import pytest

from retarget.geometry import rotations as rot
from retarget.motion.device_recording import DeviceRecording
from retarget.motion.device_stream import (
    align_to,
    hold_untracked,
    resample_stream,
    resample_tracked,
)

Z = np.array([0.0, 0.0, 1.0])


def recording(hz: float = 90.0, seconds: float = 2.0) -> DeviceRecording:
    t = 0.25 + np.arange(int(seconds * hz) + 1) / hz  # a stream that does not start at 0
    poses = np.zeros((len(t), 3, 7))
    for d in range(3):
        poses[:, d, 0] = 0.5 * t + d  # linear motion: exact under linear interpolation
        poses[:, d, 1] = -0.2 * t
        poses[:, d, 2] = 1.0 + 0.1 * d
        poses[:, d, 3:] = rot.from_axis_angle(Z, 0.3 * t)  # steady turn: exact under slerp
    return DeviceRecording(t, poses, np.ones((len(t), 3), bool))


def test_resampling_is_exact_for_linear_motion_and_steady_turns() -> None:
    rec = recording()
    out = resample_stream(rec, 36.0)
    assert out.shape == (int(2.0 * 36) + 1, 3, 7)
    q = np.arange(len(out)) / 36.0 + 0.25
    np.testing.assert_allclose(out[:, 1, 0], 0.5 * q + 1, atol=1e-9)
    np.testing.assert_allclose(out[:, 2, 1], -0.2 * q, atol=1e-9)
    expected = rot.from_axis_angle(Z, 0.3 * q)
    assert np.all(rot.angle(rot.mul(rot.conj(expected), out[:, 0, 3:])) < 1e-7)


def test_untracked_samples_hold_the_last_tracked_pose() -> None:
    rec = recording()
    rec.tracked[10:20, 2] = False  # right controller lost for 10 samples
    rec.tracked[:5, 1] = False  # left controller found late
    rec.poses[~rec.tracked] = np.nan  # readers leave nothing usable there
    held = hold_untracked(rec)
    assert np.isfinite(held).all()
    np.testing.assert_array_equal(held[10:20, 2], np.repeat(rec.poses[9:10, 2], 10, axis=0))
    np.testing.assert_array_equal(held[:5, 1], np.repeat(rec.poses[5:6, 1], 5, axis=0))


def test_resampled_frames_say_which_devices_were_tracked() -> None:
    rec = recording()  # 90 Hz from t = 0.25
    rec.tracked[11:19, 2] = False  # samples 11..18: 0.122 .. 0.200 s into the stream
    flags = resample_tracked(rec, 36.0)
    assert flags.shape == resample_stream(rec, 36.0).shape[:2]
    assert flags[:, :2].all()
    lost = np.flatnonzero(~flags[:, 2])
    np.testing.assert_array_equal(lost, [5, 6, 7])  # frames at 0.139 .. 0.194 s


def test_calibration_puts_the_first_headset_on_the_target_and_keeps_the_geometry() -> None:
    poses = resample_stream(recording(), 36.0)
    target = np.concatenate([[3.0, -1.0, 1.6], rot.from_axis_angle(Z, np.array(2.0))])
    aligned = align_to(poses, target)
    np.testing.assert_allclose(aligned[0, 0, :2], target[:2], atol=1e-9)
    assert abs(np.angle(np.exp(1j * (rot.yaw(aligned[0, 0, 3:]) - 2.0)))) < 1e-9
    np.testing.assert_allclose(aligned[..., 2], poses[..., 2], atol=1e-12)  # heights kept
    dist = np.linalg.norm(poses[:, :, None, :3] - poses[:, None, :, :3], axis=-1)
    dist_aligned = np.linalg.norm(aligned[:, :, None, :3] - aligned[:, None, :, :3], axis=-1)
    np.testing.assert_allclose(dist_aligned, dist, atol=1e-9)
    np.testing.assert_allclose(np.linalg.norm(aligned[..., 3:], axis=-1), 1.0, atol=1e-12)


def test_scaled_calibration_puts_the_user_at_the_characters_size() -> None:
    """With ``scale`` (runs with ``env.devices: character``) the first headset lands at the
    target's height too and every distance grows by the same ratio; the live calibration maps
    the room in and back out by it; a user who is not standing at the start is refused."""
    from retarget.live.calibration import Calibration
    from retarget.motion.device_stream import height_scale

    poses = resample_stream(recording(), 36.0)
    target = np.concatenate([[3.0, -1.0, 2.0], rot.from_axis_angle(Z, np.array(2.0))])
    aligned = align_to(poses, target, scale=True)
    k = 2.0 / poses[0, 0, 2]
    assert height_scale(poses[0, 0], target) == k and k != 1.0
    np.testing.assert_allclose(aligned[0, 0, :3], target[:3], atol=1e-9)
    np.testing.assert_allclose(aligned[..., 2], k * poses[..., 2], atol=1e-12)
    dist = np.linalg.norm(poses[:, :, None, :3] - poses[:, None, :, :3], axis=-1)
    dist_aligned = np.linalg.norm(aligned[:, :, None, :3] - aligned[:, None, :, :3], axis=-1)
    np.testing.assert_allclose(dist_aligned, k * dist, atol=1e-9)
    cal = Calibration.between(poses[0, 0], target, scale=True)
    np.testing.assert_allclose(cal.to_world(poses[-1]), aligned[-1], atol=1e-9)
    np.testing.assert_allclose(cal.to_room(cal.to_world(poses[-1])), poses[-1], atol=1e-9)
    sitting = poses[0, 0].copy()
    sitting[2] = 0.1
    with pytest.raises(ValueError, match="standing"):
        height_scale(sitting, target)
