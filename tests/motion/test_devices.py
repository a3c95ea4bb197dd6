"""Device synthesis, augmentation, recording format and OpenXR/Unity conventions."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from retarget.errors import MotionError
from retarget.geometry import rotations as rot
from retarget.motion import skeleton as sk
from retarget.motion.clip import MotionClip
from retarget.motion.device_recording import (
    DeviceRecording,
    convert,
    read_recording,
    write_recording,
)
from retarget.motion.devices import DeviceNoise, device_poses, mount_offsets, perturb
from retarget.motion.procedural import default_motions


def _random_poses(shape, seed=0) -> np.ndarray:
    rng = np.random.default_rng(seed)
    return np.concatenate([rng.normal(size=(*shape, 3)),
                           rot.normalize(rng.normal(size=(*shape, 4)))], -1)


def _same_pose(a: np.ndarray, b: np.ndarray) -> bool:
    pos = np.abs(a[..., :3] - b[..., :3]).max() < 1e-9
    ang = rot.angle(rot.mul(rot.conj(a[..., 3:]), b[..., 3:])).max() < 1e-7
    return bool(pos and ang)


def test_tpose_devices_sit_at_head_and_hands():
    clip = MotionClip(30.0, np.array([[0.0, 0.0, 1.0]]), rot.identity((1, sk.NUM_JOINTS)),
                      sk.rest_offsets())
    d = device_poses(clip.global_pos, clip.global_rot)
    g = clip.global_pos[0]
    assert np.allclose(d[0, 0, :3], g[sk.joint_index("head")] + [0.09, 0, 0.08])
    assert np.allclose(d[0, 1, :3], g[sk.joint_index("left_wrist")] + [0, 0.08, -0.02])
    assert np.allclose(d[0, 2, :3], g[sk.joint_index("right_wrist")] + [0, -0.08, -0.02])
    assert np.allclose(d[0, :, 3:], rot.identity((3,)))
    assert np.allclose(mount_offsets(1.5), mount_offsets() * 1.5 / 1.75)


def test_headset_follows_head_rotation_and_batches():
    walk = default_motions(names=("idle",))[0]  # idle looks around +-25 deg
    d = device_poses(walk.global_pos, walk.global_rot)
    head = walk.global_rot[:, sk.joint_index("head")]
    assert np.allclose(rot.yaw(d[:, 0, 3:]), rot.yaw(head))
    assert np.ptp(np.degrees(rot.yaw(d[:, 0, 3:]))) > 40
    batched = device_poses(walk.global_pos.reshape(4, -1, sk.NUM_JOINTS, 3),
                           walk.global_rot.reshape(4, -1, sk.NUM_JOINTS, 4))
    assert batched.shape == (4, walk.num_frames // 4, 3, 7)
    assert np.allclose(batched.reshape(-1, 3, 7), d)


def test_latency_dropout_and_noise():
    poses = _random_poses((50, 8, 3))  # (T, N, D, 7)
    rng = np.random.default_rng(0)
    late, tracked = perturb(poses, DeviceNoise(latency=3), rng)
    assert np.array_equal(late[3:], poses[:-3]) and np.array_equal(late[:3], poses[[0, 0, 0]])
    assert tracked.all()
    held, tracked = perturb(poses, DeviceNoise(dropout=0.3), rng)
    assert 0.2 < 1 - tracked.mean() < 0.4
    for t in range(1, 50):  # untracked samples repeat the previous reported pose
        lost = ~tracked[t]
        assert np.array_equal(held[t][lost], held[t - 1][lost])
        assert np.array_equal(held[t][~lost], poses[t][~lost])
    noisy, _ = perturb(poses, DeviceNoise(position_std=0.01, rotation_std=0.02), rng)
    assert 0.008 < np.std(noisy[..., :3] - poses[..., :3]) < 0.012
    ang = rot.angle(rot.mul(rot.conj(poses[..., 3:]), noisy[..., 3:]))
    assert 0.01 < np.median(ang) < 0.04
    # time axis elsewhere
    moved, _ = perturb(np.swapaxes(poses, 0, 1), DeviceNoise(latency=2), rng, time_axis=1)
    assert np.array_equal(np.swapaxes(moved, 0, 1)[2:], poses[:-2])


@pytest.mark.parametrize("convention", ["openxr", "unity"])
def test_convention_round_trip(convention):
    poses = _random_poses((100, 3))
    there = convert(poses, "retarget", convention)
    assert _same_pose(convert(there, convention, "retarget"), poses)


def test_convention_semantics():
    """A point 1 m ahead, 2 m left, 3 m up; a device yawed 90 deg to the left."""
    pose = np.concatenate([[1.0, 2.0, 3.0], rot.from_axis_angle(np.array([0, 0, 1.0]),
                                                               np.pi / 2)])
    oxr = convert(pose, "retarget", "openxr")  # x right, y up, -z forward
    assert np.allclose(oxr[:3], [-2.0, 3.0, -1.0])
    # turning left is a positive rotation about +Y (up) in OpenXR
    assert np.allclose(np.abs(oxr[3:]), np.abs(rot.from_axis_angle(np.array([0, 1.0, 0]),
                                                                   np.pi / 2)))
    uni = convert(pose, "retarget", "unity")  # x right, y up, z forward, left-handed
    assert np.allclose(uni[:3], [-2.0, 3.0, 1.0])
    # Unity is left-handed: turning left is a negative rotation about +Y
    assert np.allclose(uni[3:] * np.sign(uni[3]),
                       rot.from_axis_angle(np.array([0, 1.0, 0]), -np.pi / 2))
    ident = np.array([0, 0, 0, 1.0, 0, 0, 0])
    for c in ("openxr", "unity"):
        assert np.allclose(convert(ident, "retarget", c), ident)


@pytest.mark.parametrize("convention", ["retarget", "openxr", "unity"])
def test_recording_round_trip(convention, tmp_path: Path):
    poses = _random_poses((20, 3), seed=1)
    tracked = np.ones((20, 3), bool)
    tracked[5:8, 1] = False
    rec = DeviceRecording(np.arange(20) / 72.0, poses, tracked)
    path = write_recording(tmp_path / "r.jsonl", rec, convention)
    assert json.loads(path.read_text().splitlines()[0])["convention"] == convention
    back = read_recording(path)
    assert np.array_equal(back.tracked, tracked)
    assert np.allclose(back.time, rec.time)
    ok = tracked
    assert np.abs(back.poses[ok][:, :3] - poses[ok][:, :3]).max() < 1e-6
    assert rot.angle(rot.mul(rot.conj(back.poses[ok][:, 3:]), poses[ok][:, 3:])).max() < 1e-5
    assert np.allclose(back.poses[5:8, 1], back.poses[4, 1])  # held while lost


@pytest.mark.parametrize("line,expect", [
    ('{"t": 0, "hmd": [0,0,0,1,0,0,0], "left": null, "right": [1,2]}', "7 finite"),
    ('{"t": "x"}', "finite time"),
    ("not json", "not JSON"),
    ('{"t": 0, "hmd": [0,0,0,2,2,2,2]}', "unit length"),
    ('{"t": true, "hmd": [0,0,0,1,0,0,0]}', "finite time"),
    ('{"t": 0, "hmd": [0,0,true,1,0,0,0]}', "7 finite"),
    ('{"t": 1e9, "hmd": [0,0,0,1,0,0,0]}', "at most 10 s apart"),
    ('{"t": 0, "hmd": [5000,0,1.6,1,0,0,0]}', "at most 100 m away"),
])
def test_recording_errors_name_the_line(line, expect, tmp_path: Path):
    path = tmp_path / "bad.jsonl"
    header = '{"format": "retarget-devices", "version": 1, "convention": "openxr"}'
    path.write_text(header + "\n" + '{"t": -1}\n' + line + "\n")
    with pytest.raises(MotionError, match=expect) as info:
        read_recording(path)
    assert info.value.line == 3 and info.value.file == str(path)


def test_a_recording_where_nothing_is_tracked_is_refused(tmp_path: Path):
    path = tmp_path / "lost.jsonl"
    header = '{"format": "retarget-devices", "version": 1}'
    samples = [f'{{"t": {k / 72}, "hmd": null, "left": null, "right": null}}' for k in range(5)]
    path.write_text("\n".join([header, *samples]) + "\n")
    with pytest.raises(MotionError, match="no device is tracked"):
        read_recording(path)


def test_an_hours_long_recording_is_refused_before_it_is_resampled(tmp_path: Path):
    path = tmp_path / "long.jsonl"
    header = '{"format": "retarget-devices", "version": 1}'
    samples = [f'{{"t": {k * 9.0}, "hmd": [0,0,1.6,1,0,0,0]}}' for k in range(1202)]
    path.write_text("\n".join([header, *samples]) + "\n")
    with pytest.raises(MotionError, match="longer than 3 h"):
        read_recording(path)
