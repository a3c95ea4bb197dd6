"""Every shared real clip (CMU 3dsMax naming, Bandai Namco) read onto the canonical skeleton."""

from __future__ import annotations

import numpy as np
import pytest

from retarget.motion import skeleton as sk
from retarget.motion.floor import foot_points, sole_heights


def test_all_clips_load_with_header_frame_counts(real_clips, mocap_index):
    assert set(real_clips) == set(mocap_index)
    for name, clip in real_clips.items():
        row = mocap_index[name]
        assert clip.num_frames == int(row["frames"]), name
        assert clip.fps == pytest.approx(float(row["fps"]), rel=1e-4), name
        assert np.isfinite(clip.local_rot).all() and np.isfinite(clip.root_pos).all()


def test_detected_skeleton_units_and_up(real_clips):
    for name, clip in real_clips.items():
        expected = ("cmu_3dsmax", "cmu") if name.startswith("cmu") else ("bandai", "cm")
        assert (clip.skeleton, clip.meta["units"]) == expected, name
        assert clip.meta["up"] == "+y", name


def test_standing_height_is_adult(real_clips):
    heights = {n: round(c.height, 3) for n, c in real_clips.items()}
    print("\nsubject heights (m):", heights)
    for name, h in heights.items():
        assert 1.5 <= h <= 1.95, (name, h)


def test_bone_lengths_constant_over_time(real_clips):
    parents = np.array(sk.PARENTS[1:])
    for name, clip in real_clips.items():
        for pos in (clip.global_pos, clip.meta["source_positions"]):
            length = np.linalg.norm(pos[:, 1:] - pos[:, parents], axis=-1)
            spread = length.max(0) - length.min(0)
            assert spread.max() < 1e-3, (name, spread.max())


def test_canonical_fk_reproduces_source_joint_positions(real_clips):
    worst = {}
    for name, clip in real_clips.items():
        err = np.linalg.norm(clip.global_pos - clip.meta["source_positions"], axis=-1).max()
        worst[name] = float(err)
        assert err < 0.01, (name, err)
    print("\nmax FK error (m):", {k: f"{v:.1e}" for k, v in worst.items()})


def _primary_child(j: int) -> int | None:
    kids = sk.children(j)
    return kids[0] if kids else None


def test_source_rest_pose_maps_to_canonical_tpose(real_clips):
    """Each subject's T-pose (identity rotations) points every limb and spine bone the way the
    canonical T-pose does, whatever the file's own rest pose (Bandai: bones along local X)."""
    rest = sk.rest_offsets()
    for name, clip in real_clips.items():
        for j in range(1, sk.NUM_JOINTS):
            c = _primary_child(j)
            if c is None or np.linalg.norm(clip.offsets[c]) < 1e-3:
                continue
            a, b = clip.offsets[c], rest[c]
            angle = np.degrees(np.arccos(np.clip(a @ b / np.linalg.norm(a) / np.linalg.norm(b),
                                                 -1, 1)))
            assert angle < 5.0, (name, sk.JOINT_NAMES[c], angle)


def _walking_frames(clip) -> np.ndarray:
    """Upright locomotion: the pelvis moves faster than 0.3 m/s and is not crouched (within
    10% of its median height; CMU 131_01 dips into a deep crouch and glides out of it)."""
    root = clip.root_pos[:, :2]
    speed = np.linalg.norm(np.gradient(root, axis=0), axis=-1) * clip.fps
    upright = clip.root_pos[:, 2] >= 0.9 * np.median(clip.root_pos[:, 2])
    return (speed > 0.3) & upright


def test_floor_alignment_on_walking_frames(real_clips):
    report = {}
    for name, clip in real_clips.items():
        if "walk" not in name:
            continue
        walking = _walking_frames(clip)
        assert walking.sum() > 0.2 * clip.num_frames, name
        sole = sole_heights(foot_points(clip), clip.meta["foot_clearance"]).min(axis=1)[walking]
        inside = np.abs(sole) <= 0.03
        report[name] = (round(float(inside.mean()), 3), round(float(np.abs(sole).max()), 3))
        if name.startswith("bandai"):
            assert inside.all(), (name, report[name])
        else:
            # CMU 131 is a Michael-Jackson-styled walk with dance moves: e.g. at 3.8-4.0 s of
            # 131_01 the subject rises on one foot out of a crouch with the sole 3.5-3.7 cm up
            # (seen in `motion show`); 5% of its moving frames are such moves
            assert inside.mean() >= 0.94, (name, report[name])
    print("\nwalking frames within +-3 cm, max |lowest sole| (m):", report)


def test_contact_ratios_are_plausible(real_clips):
    report = {}
    for name, clip in real_clips.items():
        c = clip.contacts
        left, right, both = c[:, 0].mean(), c[:, 1].mean(), c.all(axis=1).mean()
        report[name] = (round(float(left), 2), round(float(right), 2), round(float(both), 2))
        if "wave" in name or "raise" in name:
            assert min(left, right) > 0.95, (name, report[name])
        elif name.startswith("bandai_d2_walk"):
            assert 0.4 <= left <= 0.75 and 0.4 <= right <= 0.75, (name, report[name])
            assert both < 0.35, (name, report[name])
        elif "run" in name:
            assert max(left, right) < 0.5 and both < 0.02, (name, report[name])
        else:
            assert min(left, right) >= 0.3 and max(left, right) <= 0.98, (name, report[name])
    print("\ncontact ratios (left, right, both):", report)
