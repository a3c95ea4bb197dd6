"""Mirroring, resampling, generated motions, motion sources."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from retarget.errors import MotionError
from retarget.geometry import rotations as rot
from retarget.motion import skeleton as sk
from retarget.motion.floor import foot_points
from retarget.motion.mirror import mirror
from retarget.motion.procedural import default_motions
from retarget.motion.resample import resample
from retarget.motion.sources import ENV_VAR, load_motions, resolve_motion_source


@pytest.fixture(scope="module")
def generated():
    return {c.name: c for c in default_motions()}


def test_mirror_reflects_positions_and_swaps_sides(generated):
    clip = generated["turn_left"]
    m = mirror(clip)
    perm = np.array(sk.LEFT_RIGHT)
    assert np.allclose(m.global_pos, clip.global_pos[:, perm] * [1, -1, 1], atol=1e-9)
    assert np.array_equal(m.contacts, clip.contacts[:, ::-1])
    # a left turn mirrored is a right turn; mirroring twice is the identity
    yaw = np.unwrap(rot.yaw(m.global_rot[:, 0]))
    assert yaw[-1] - yaw[0] < -1.0
    twice = mirror(m)
    assert np.allclose(twice.global_pos, clip.global_pos, atol=1e-9)


def test_resample_keeps_duration_and_interpolates(generated):
    clip = generated["walk"]  # 60 fps
    r36 = resample(clip, 36.0)
    assert r36.fps == 36.0
    assert abs(r36.duration - clip.duration) < 1 / 36
    # frames that fall on source frames are exact (t = k/12 s)
    assert np.allclose(r36.global_pos[::3], clip.global_pos[::5][: len(r36.global_pos[::3])],
                       atol=1e-9)
    # a slerp midpoint lies halfway in angle between its neighbours
    r120 = resample(clip, 120.0)
    a, mid, b = clip.local_rot[10], r120.local_rot[21], clip.local_rot[11]
    assert np.allclose(rot.angle(rot.mul(rot.conj(a), mid)),
                       rot.angle(rot.mul(rot.conj(mid), b)), atol=1e-6)


def test_resampled_real_clip_stays_on_its_path(real_clips):
    clip = real_clips["bandai_d2_walk_normal_020.bvh"]
    r = resample(clip, 36.0)
    t = np.arange(r.num_frames) / 36.0
    src = np.interp(t, np.arange(clip.num_frames) / clip.fps, clip.global_pos[:, 13, 0])
    assert np.abs(r.global_pos[:, 13, 0] - src).max() < 0.01


def test_generated_feet_stay_planted_in_contact(generated):
    for name, clip in generated.items():
        pts = foot_points(clip)
        speed = np.linalg.norm(np.gradient(pts, axis=0) * clip.fps, axis=-1).min(axis=1)
        for k in range(2):
            planted = clip.contacts[:, k]
            assert planted.mean() > 0.5, name
            # inside a contact phase (not its first/last frame) the sole is still
            inner = planted & np.roll(planted, 1) & np.roll(planted, -1)
            assert np.median(speed[inner, k]) < 0.05, (name, np.median(speed[inner, k]))
        lowest = (pts[..., 2] - clip.meta["foot_clearance"]).min(axis=(1, 2))
        assert np.abs(lowest).max() < 0.01, name


def test_generated_set_content(generated):
    assert set(generated) == {"idle", "walk", "turn_left", "turn_right", "sit_stand"}
    walk = generated["walk"]
    travelled = np.linalg.norm(walk.root_pos[-1, :2] - walk.root_pos[0, :2])
    assert 6.0 < travelled < 10.0
    assert 0.5 < walk.contacts.mean() < 0.75
    sit = generated["sit_stand"]
    assert sit.root_pos[:, 2].min() < 0.6 < sit.root_pos[0, 2]
    assert sit.root_pos[-1, 2] == pytest.approx(sit.root_pos[0, 2], abs=0.01)
    small = default_motions(1.5, names=("walk",))[0]
    assert small.height == pytest.approx(1.5, rel=1e-6)


def test_motion_sources(tmp_path: Path, monkeypatch: pytest.MonkeyPatch, mocap_dir: Path):
    monkeypatch.delenv(ENV_VAR, raising=False)
    assert resolve_motion_source(None) is None
    assert [c.name for c in load_motions(None)][:2] == ["idle", "walk"]
    monkeypatch.setenv(ENV_VAR, str(mocap_dir))
    assert len(resolve_motion_source(None)) == 14
    one = mocap_dir / "bandai_d2_run_normal_040.bvh"
    assert resolve_motion_source(one) == [one]
    with pytest.raises(MotionError, match="does not exist"):
        resolve_motion_source(tmp_path / "missing")
    with pytest.raises(MotionError, match="no motion files"):
        resolve_motion_source(tmp_path)
    (tmp_path / "x.fbx").write_text("")
    from retarget import load_plugins
    from retarget.motion.sources import reader_for

    formats = load_plugins().motion_formats()
    with pytest.raises(MotionError, match=r"known: \.bvh"):
        reader_for(tmp_path / "x.fbx", formats)
    with pytest.raises(ValueError, match="motion_formats"):  # files named, no readers given
        load_motions(str(one))
    monkeypatch.delenv(ENV_VAR)
