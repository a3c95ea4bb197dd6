"""``benchmarks/device_lag.py``: how much of a policy's device error is lag."""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).parents[2] / "benchmarks"))
from device_lag import device_bias, lag_errors, measure

from retarget.motion.bvh_write import write_bvh
from retarget.motion.procedural import default_motions


def test_a_delayed_copy_is_found_at_its_delay() -> None:
    """A body that does at step t what the reference did at t - 3 is 3 steps late, with no
    error left once that is forgiven; the error at lag 0 is its speed times the delay."""
    t = np.arange(60) * 0.1
    ref = np.zeros((60, 2, 3, 3))
    ref[..., 0] = t[:, None, None]  # every site moves 0.1 m per step along x
    sim = np.concatenate([np.repeat(ref[:1], 3, axis=0), ref[:-3]])
    ok = np.ones((60, 2), dtype=bool)
    lags = lag_errors([{"sim": sim, "ref": ref, "ok": ok}], max_lag=6)
    head = np.array(lags["head_cm"])
    assert int(head.argmin()) == 3 and head[3] < 1e-9
    assert 25 < head[0] < 30  # 0.3 m behind, but the first 3 steps stand still
    assert np.array(lags["hands_cm"]).argmin() == 3
    assert max(lags["head_up_cm"]) == 0.0  # it moved along x only


def test_steps_not_tracked_are_left_out() -> None:
    ref = np.zeros((10, 1, 3, 3))
    sim = ref.copy()
    sim[5:] += 10.0  # far off once it failed
    ok = np.ones((10, 1), dtype=bool)
    ok[5:] = False
    assert lag_errors([{"sim": sim, "ref": ref, "ok": ok}], max_lag=0)["head_cm"][0] == 0.0


def test_a_steady_offset_is_reported_in_the_headset_heading_frame() -> None:
    """A body 2 cm lower than the reference with its left hand 3 cm further left, walking
    along world +y (heading 90 degrees): forward/left/up are the walker's, not the world's."""
    ref = np.zeros((20, 2, 3, 3))
    sim = ref.copy()
    sim[..., 2] -= 0.02
    sim[:, :, 1, 0] -= 0.03  # world -x is the walker's left when it faces +y
    quat = np.zeros((20, 2, 4))
    quat[..., 0] = quat[..., 3] = np.sqrt(0.5)  # 90 degrees about +z
    ok = np.ones((20, 2), dtype=bool)
    ok[10:, 1] = False
    sim[10:, 1] += 5.0  # a failed run's steps are left out
    bias = device_bias([{"sim": sim, "ref": ref, "ok": ok, "head_quat": quat}])
    np.testing.assert_allclose(bias["head"], [0.0, 0.0, -2.0], atol=1e-6)
    np.testing.assert_allclose(bias["left_hand"], [0.0, 3.0, -2.0], atol=1e-6)
    np.testing.assert_allclose(bias["right_hand"], [0.0, 0.0, -2.0], atol=1e-6)


def test_a_shipped_student_is_measured_on_a_clip(tmp_path: Path) -> None:
    """A real rollout: the pretrained three-point student on a generated walk."""
    clip = write_bvh(default_motions(names=("walk",))[0], tmp_path / "walk.bvh")
    r = measure("pretrained:human-three_point-student", [clip], num_envs=1, max_lag=4)
    assert len(r["by_lag"]["head_cm"]) == 5 and r["clips"] == 1
    assert 0 < r["head_cm_best"] <= r["head_cm_now"] < 100
    assert 0 <= r["head_lag_steps"] <= 4
    assert set(r["bias_cm"]) == {"head", "left_hand", "right_hand"}
    assert all(len(v) == 3 and np.isfinite(v).all() for v in r["bias_cm"].values())
