"""``benchmarks/heldout_eval.py --by-speed``: clips pooled by the performer's ground speed."""

from __future__ import annotations

import sys
from pathlib import Path

import pytest

import retarget
from retarget.motion.bvh_write import write_bvh
from retarget.motion.procedural import default_motions

sys.path.insert(0, str(Path(__file__).parents[2] / "benchmarks"))
from heldout_eval import by_speed, ground_speed


def test_clips_are_pooled_slowest_first_with_their_own_figures(tmp_path) -> None:
    idle, walk, turn = default_motions(names=("idle", "walk", "turn_left"))
    files = [write_bvh(c, tmp_path / f"{c.name}.bvh") for c in (walk, idle, turn)]
    formats = retarget.load_plugins().motion_formats()
    speeds = {f.stem: ground_speed(f, formats) for f in files}
    assert speeds["idle"] < 0.05 and speeds["walk"] == pytest.approx(1.1, rel=0.15), speeds
    figures = {"idle": {"phc_success": 1.0, "headset_cm": 2.0},
               "walk": {"phc_success": 0.0, "headset_cm": 30.0},
               "turn_left": {"phc_success": 1.0, "headset_cm": 10.0}}  # fmt: skip
    table = by_speed(files, figures, 2)
    assert [r["clips"] for r in table] == [2, 1]
    slow, fast = table
    assert slow["speed_from"] <= slow["speed_to"] <= fast["speed_from"]
    assert fast["phc_success"] == 0.0 and fast["headset_cm"] == 30.0  # the walk is the fastest
    assert slow["phc_success"] == 1.0 and slow["headset_cm"] == pytest.approx(6.0)
    assert slow["falls_per_min"] != slow["falls_per_min"]  # no clip gave it: NaN, not 0


def test_clips_the_report_lacks_are_left_out(tmp_path) -> None:
    (idle,) = default_motions(names=("idle",))
    files = [write_bvh(idle, tmp_path / "idle.bvh"), tmp_path / "never_evaluated.bvh"]
    table = by_speed(files, {"idle": {"phc_success": 1.0}}, 3)
    assert [r["clips"] for r in table] == [1]
