"""Camera frames beside a device recording: written and read back exactly, matched by time,
and every malformed file refused naming the file and the array (no pickle, bounded size)."""

from __future__ import annotations

import json
import zipfile

import numpy as np
import pytest

from retarget.errors import MotionError
from retarget.motion import device_frames
from retarget.motion.camera_rigs import RIGS
from retarget.motion.device_frames import RecordedFrames, frames_path, read_frames, write_frames
from retarget.motion.device_recording import DeviceRecording, read_recording, write_recording

RIG = RIGS["aria"].model_dump_json()


def frames(count: int = 5, start: float = 10.0) -> RecordedFrames:
    images = np.random.default_rng(1).integers(0, 256, (count, 2, 6, 8), dtype=np.uint8)
    return RecordedFrames(start + np.arange(count) / 30.0, images, RIG)


def recording(start: float = 10.0) -> DeviceRecording:
    poses = np.zeros((4, 3, 7))
    poses[..., 3] = 1.0
    poses[..., 2] = 1.6
    return DeviceRecording(start + np.arange(4) / 20.0, poses, np.ones((4, 3), dtype=bool))


def test_frames_round_trip_beside_the_recording(tmp_path) -> None:
    rec = recording()
    rec.frames = frames()
    path = write_recording(tmp_path / "me.jsonl", rec, convention="openxr")
    assert frames_path(path) == tmp_path / "me.frames.npz" and frames_path(path).is_file()
    back = read_recording(path)
    assert back.frames is not None
    np.testing.assert_array_equal(back.frames.images, rec.frames.images)
    np.testing.assert_allclose(back.frames.time, rec.frames.time)
    assert back.frames.rig == RIG
    # the latest frame taken at or before each time (before the first: the first)
    picks = back.frames.latest(np.array([9.0, 10.0, 10.02, 10.034, 99.0]))
    assert picks.tolist() == [0, 0, 0, 1, 4]
    # a recording without a frames file has none
    assert read_recording(write_recording(tmp_path / "bare.jsonl", recording())).frames is None


def test_frames_on_another_clock_are_refused(tmp_path) -> None:
    rec = recording()
    rec.frames = frames(start=500.0)
    path = write_recording(tmp_path / "me.jsonl", rec)
    with pytest.raises(MotionError, match=r"me\.frames\.npz.*share one clock"):
        read_recording(path)


def _write(path, **arrays) -> None:
    np.savez(path, **arrays)


@pytest.mark.parametrize(
    ("change", "message"),
    [
        ({"images": None}, "lacks images"),
        ({"images": np.zeros((3, 2, 6, 8), np.float32)}, "must be uint8"),
        ({"images": np.zeros((3, 9, 6, 8), np.uint8)}, "1-8 cameras"),
        ({"images": np.zeros((3, 2, 6, 8000), np.uint8)}, "at most 640 pixels"),
        ({"t": np.array([0.0, 0.1])}, "3 finite seconds"),
        ({"t": np.array([0.0, 0.2, 0.1])}, "not increasing at frame 2"),
        ({"t": np.array([0.0, np.nan, 0.2])}, "finite seconds"),
        ({"rig": np.array(["not json"])}, "one string"),
        ({"rig": np.array("{\"cameras\": []}")}, "not a camera rig"),
        ({"rig": np.array(RIGS["quest2"].model_dump_json())}, "4 cameras but 'images' 2"),
        ({"rig": np.array([{"a": 1}], dtype=object)}, "cannot read frames"),
    ],
)
def test_malformed_frames_name_the_file_and_array(tmp_path, change, message) -> None:
    arrays = {"t": np.arange(3) / 30.0, "images": np.zeros((3, 2, 6, 8), np.uint8),
              "rig": np.array(RIG)}  # fmt: skip
    arrays.update(change)
    path = tmp_path / "bad.frames.npz"
    _write(path, **{k: v for k, v in arrays.items() if v is not None})
    with pytest.raises(MotionError, match=message) as info:
        read_frames(path)
    assert "bad.frames.npz" in str(info.value)


def test_not_a_zip_and_oversized_images_are_refused_before_reading(tmp_path, monkeypatch) -> None:
    junk = tmp_path / "junk.frames.npz"
    junk.write_text(json.dumps({"t": [0]}))
    with pytest.raises(MotionError, match="not a frames file"):
        read_frames(junk)
    path = write_frames(tmp_path / "big.frames.npz", frames())
    with zipfile.ZipFile(path) as archive:
        size = archive.getinfo("images.npy").file_size
    monkeypatch.setattr(device_frames, "MAX_BYTES", size - 1)
    with pytest.raises(MotionError, match="GiB"):
        read_frames(path)
