"""Headset camera views: rigs, the renderer, and the on-disk cache keyed by content."""

from __future__ import annotations

import numpy as np
import pytest

from retarget.motion.camera_rigs import RIGS, Camera
from retarget.motion.devices import device_poses
from retarget.motion.procedural import default_motions
from retarget.render import ego_cache
from retarget.render.ego import EgoRenderer

WALK = next(c for c in default_motions() if c.name.startswith("walk"))
HEADSETS = device_poses(WALK.global_pos, WALK.global_rot, WALK.height)[:, 0]


def _inputs(frames: slice = slice(0, 6)):
    joints = WALK.global_pos[frames]
    return joints, HEADSETS[frames], np.full(len(joints), WALK.height)


def test_a_camera_looking_ahead_has_its_axis_along_the_headset_x() -> None:
    from retarget.geometry import rotations as rot

    ahead = Camera(name="c", pos=(0, 0, 0)).quat()
    np.testing.assert_allclose(rot.apply(ahead, np.array([0, 0, -1.0])), [1, 0, 0], atol=1e-9)
    np.testing.assert_allclose(rot.apply(ahead, np.array([0, 1.0, 0])), [0, 0, 1], atol=1e-9)
    down_left = Camera(name="c", pos=(0, 0, 0), yaw=90, pitch=-30).quat()
    axis = rot.apply(down_left, np.array([0, 0, -1.0]))
    np.testing.assert_allclose(axis, [0, np.cos(np.radians(30)), -0.5], atol=1e-9)


def test_the_rig_renders_grayscale_views_that_see_the_body() -> None:
    joints, headsets, heights = _inputs()
    with EgoRenderer(RIGS["quest2"], 48, 36) as render:
        views = render(joints[3], headsets[3], float(heights[3]))
        far = joints[3] + np.array([50.0, 0.0, 0.0])  # the same person 50 m away
        empty = render(far, headsets[3], float(heights[3]))
    assert views.shape == (4, 36, 48) and views.dtype == np.uint8
    low = slice(0, 2)  # the downward cameras see the legs walking below
    assert np.abs(views[low].astype(int) - empty[low]).mean() > 1.0


def test_cache_hit_miss_by_content_and_images_match_a_direct_render(tmp_path, monkeypatch) -> None:
    joints, headsets, heights = _inputs()
    rig = RIGS["aria"]
    first = ego_cache.ego_images(joints, headsets, heights, rig, 32, 24, folder=tmp_path,
                                 progress=False)  # fmt: skip
    assert first.shape == (6, 2, 24, 32) and len(list(tmp_path.glob("*.npy"))) == 1
    with EgoRenderer(rig, 32, 24) as render:
        np.testing.assert_array_equal(first[4], render(joints[4], headsets[4], WALK.height))

    def no_rendering(*args, **kwargs):
        raise AssertionError("a cache hit must not render")

    monkeypatch.setattr(ego_cache, "render_into", no_rendering)
    again = ego_cache.ego_images(joints, headsets, heights, rig, 32, 24, folder=tmp_path)
    np.testing.assert_array_equal(again, first)  # memory-mapped from the file
    moved = joints.copy()
    moved[2, 5, 0] += 0.01  # one joint of one frame moved by 1 cm: another key
    key = ego_cache.cache_key
    assert key(moved, headsets, heights, rig, 32, 24) != key(joints, headsets, heights, rig, 32, 24)
    assert key(joints, headsets, heights, RIGS["quest2"], 32, 24) != key(
        joints, headsets, heights, rig, 32, 24
    )
    with pytest.raises(AssertionError, match="must not render"):
        ego_cache.ego_images(moved, headsets, heights, rig, 32, 24, folder=tmp_path)
