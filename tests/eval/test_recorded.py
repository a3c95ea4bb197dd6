"""Driving a run from recorded devices as a VR user does (``retarget.eval.recorded``) and
``benchmarks/follow_recordings.py``, which measures it on held-out performers."""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pytest
import torch

from retarget.eval.recorded import drive_recordings, follow, follow_figures
from retarget.motion.device_recording import read_recording
from retarget.registry.loader import load_plugins

sys.path.insert(0, str(Path(__file__).parents[2] / "benchmarks"))
from follow_recordings import lose_controllers, performer_recording

REGISTRY = load_plugins(strict=True)
SAMPLE = Path(__file__).parents[2] / "examples" / "recordings" / "walk_openxr.jsonl"
RUN = "pretrained:human-three_point-student"


def _shorter(rec, seconds: float):
    from retarget.motion.device_recording import DeviceRecording

    keep = rec.time - rec.time[0] <= seconds
    return DeviceRecording(rec.time[keep], rec.poses[keep], rec.tracked[keep])


def test_each_environment_plays_its_own_recording_as_it_would_alone() -> None:
    rec = read_recording(SAMPLE)
    short = _shorter(rec, 1.0)
    both = drive_recordings(RUN, REGISTRY, [rec, short])
    assert both.lengths[1] < both.lengths[0] and len(both.rows[1]) == both.lengths[1]
    lib = both.loaded.env.library
    # calibrated to the character: both start on the idle body's headset, standing
    first = [int(r[0]) for r in both.rows]
    torch.testing.assert_close(lib.devices[first[0]], lib.devices[first[1]])
    gaps = follow(both)
    assert [len(g) for g in gaps] == [n - 1 for n in both.lengths]
    assert gaps[0][0] < 0.15  # the avatar starts under the headset
    alone = follow(drive_recordings(RUN, REGISTRY, [short]))[0]
    np.testing.assert_allclose(gaps[1], alone, atol=1e-4)  # a batch changes nothing


def test_a_character_shaped_unlike_the_person_starts_under_its_headset() -> None:
    """The Dino's head stands 0.6 m from the calibrated headset of the person driving it; the
    gap is read from where the headset sits on its head (``env.headset_mount``), so standing
    still at the start is not losing the headset."""
    rec = _shorter(read_recording(SAMPLE), 0.3)
    drive = drive_recordings("pretrained:dino-hmd-student", REGISTRY, [rec])
    env = drive.loaded.env
    assert float(env.headset_mount.norm()) > 0.4
    head = env.layout.site("head")
    first = int(drive.rows[0][0])
    standing = env.reference.arrays["site_pos"][first, head]
    assert float((standing - env.library.devices[first, 0, :3]).norm()) > 0.4  # the old rule
    gaps = follow(drive)[0]
    assert gaps[0] < 0.15 and follow_figures(gaps, 30.0)["followed"] == 1.0
    human = drive_recordings(RUN, REGISTRY, [rec]).loaded.env.headset_mount
    assert float(human.norm()) < 0.1  # a human's head site is its headset mount


def test_a_height_offset_moves_every_device_up() -> None:
    rec = _shorter(read_recording(SAMPLE), 0.5)
    plain = drive_recordings(RUN, REGISTRY, [rec])
    higher = drive_recordings(RUN, REGISTRY, [rec], height_offset=0.04)
    rows = torch.as_tensor(plain.rows[0])
    a, b = plain.loaded.env.library.devices[rows], higher.loaded.env.library.devices[rows]
    torch.testing.assert_close(b[..., 2] - a[..., 2], torch.full_like(a[..., 2], 0.04))
    torch.testing.assert_close(b[..., :2], a[..., :2])


def test_a_recording_that_does_not_start_standing_is_refused() -> None:
    from retarget.motion.device_recording import DeviceRecording

    rec = read_recording(SAMPLE)
    lying = rec.poses.copy()
    lying[..., 2] = 0.1  # the headset at 10 cm: nobody stands there
    with pytest.raises(ValueError, match="standing"):
        drive_recordings(RUN, REGISTRY, [DeviceRecording(rec.time, lying, rec.tracked)])


def test_figures_of_one_stream() -> None:
    gaps = np.array([0.1, 0.2, 0.6, 0.1])
    f = follow_figures(gaps, hz=2.0)
    assert f["followed"] == 0.0 and f["lost_at_s"] == 1.0 and f["seconds"] == 2.0
    assert f["max_gap_cm"] == pytest.approx(60.0) and f["gap_cm"] == pytest.approx(25.0)
    assert follow_figures(gaps[:2], hz=2.0)["followed"] == 1.0


def test_a_performer_sets_off_from_standing() -> None:
    """The corpus's walks start mid-stride; the benchmark's recording of one starts standing
    and keeps the take after the set-off."""
    from retarget.motion.import_bvh import load_bvh
    from retarget.motion.shared_data import shared_data

    shared_walk = shared_data("mocap") / "bandai_d2_walk_normal_020.bvh"
    if not shared_walk.is_file():
        pytest.skip(f"shared mocap clip {shared_walk} not found (set RETARGET_SHARED_DATA)")
    clip = load_bvh(shared_walk)
    import retarget

    rec = performer_recording(shared_walk, retarget.load_plugins().motion_formats())
    assert rec is not None
    speed = np.linalg.norm(np.diff(rec.poses[:, 0, :2], axis=0), axis=1) / np.diff(rec.time)
    assert speed[: int(0.4 / np.diff(rec.time).mean())].max() < 0.1  # standing at first
    assert rec.time[-1] > 0.6 * clip.num_frames / clip.fps  # most of the take is kept


def test_lost_controllers_are_untracked_in_their_windows_only() -> None:
    rec = read_recording(SAMPLE)
    rec = type(rec)(rec.time, rec.poses, np.ones_like(rec.tracked))
    lost = lose_controllers(rec, 0.25)
    t = rec.time - rec.time[0]
    assert lost.tracked[:, 0].all()  # the headset is kept
    left, right = ~lost.tracked[:, 1], ~lost.tracked[:, 2]
    assert left[(t >= 2.0) & (t < 2.2)].all() and not left[t < 2.0].any()
    assert right[(t >= 3.5) & (t < 3.7)].all() and not right[t < 3.5].any()
    assert left[(t >= 5.0) & (t < 5.2)].all() and not left[(t > 2.3) & (t < 4.9)].any()
    np.testing.assert_array_equal(lost.poses, rec.poses)  # poses kept; play holds them


def test_a_recordings_lost_controllers_reach_the_sensors_as_untracked() -> None:
    """A controller the recording marks untracked is held and flagged in the library rows
    the environment reads, so a student with ``three_point.tracking`` sees it lost."""
    from retarget.motion.device_stream import resample_tracked

    rec = _shorter(read_recording(SAMPLE), 3.0)
    rec = lose_controllers(type(rec)(rec.time, rec.poses, np.ones_like(rec.tracked)), 0.25)
    drive = drive_recordings(RUN, REGISTRY, [rec])
    lib, rows = drive.loaded.env.library, torch.as_tensor(drive.rows[0])
    want = torch.as_tensor(resample_tracked(rec, lib.fps))
    assert not want[:, 1].all()  # the left controller is lost from 2.0 s
    assert torch.equal(lib.devices_tracked[rows], want)
    assert lib.devices_tracked[: int(rows[0])].all()  # the standing history is tracked
    assert bool(lib.devices_tracked[int(rows[-1]) + 1 :, 1].all()) == bool(want[-1, 1])


def test_a_run_whose_sensor_knows_its_window_once_bound_plays_a_recording(
    tmp_path: Path,
) -> None:
    """``estimated_body`` learns its device window from the estimator it wraps, when bound to
    the character; the standing history before a recording is read from the bound
    environment (the untrained estimator reads three frames: two of history)."""
    from helpers import TINY

    from retarget.cli.main import main

    recipe = tmp_path / "est.yaml"
    recipe.write_text(TINY.replace("sensors: [three_point]",
                                   "sensors: [three_point, estimated_body]"))  # fmt: skip
    assert main(["train", str(recipe), "--steps", "32", "--runs-dir", str(tmp_path),
                 "--no-tensorboard"]) == 0  # fmt: skip
    drive = drive_recordings(str(tmp_path / "tiny" / "latest"), REGISTRY,
                             [_shorter(read_recording(SAMPLE), 0.5)])  # fmt: skip
    assert drive.lead == 2 == -min(drive.loaded.env.window_offsets)
    gaps = follow(drive)[0]
    assert len(gaps) == drive.lengths[0] - 1 and np.isfinite(gaps).all()
