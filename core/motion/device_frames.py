"""Camera frames of a device recording: what the headset's own cameras saw, timestamped.

A recording ``NAME.jsonl`` (:mod:`retarget.motion.device_recording`) may have its cameras'
frames beside it in ``NAME.frames.npz`` (numpy's zip of arrays, read without pickle):

* ``t``: ``(F,)`` float64 seconds on the *same clock* as the ``.jsonl`` samples, increasing;
* ``images``: ``(F, C, H, W)`` uint8 grayscale, one view per camera of the rig, in the rig's
  camera order (already downsampled to the resolution the student reads);
* ``rig``: a 0-d string, the camera rig as JSON (``CameraRig.model_dump_json()``), so a run
  can check that the frames come from the cameras it was trained with.

Frames and poses are separate streams because cameras and trackers run at their own rates; a
reader matches them by time (each control step sees the latest frame taken by then).
"""

from __future__ import annotations

import zipfile
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from retarget.errors import MotionError

SUFFIX = ".frames.npz"
MAX_BYTES = 4 * 2**30
"""Largest image array read (4 GiB): an hour of four 64x48 views at 60 Hz is 2.6 GiB."""
MAX_CAMERAS, MAX_SIDE = 8, 640


@dataclass
class RecordedFrames:
    """Camera frames on the recording's clock."""

    time: np.ndarray  # (F,) seconds
    images: np.ndarray  # (F, C, H, W) uint8
    rig: str  # CameraRig JSON

    def latest(self, times: np.ndarray) -> np.ndarray:
        """Index of the latest frame taken at or before each of ``times`` (the first frame for
        times before it): what a live application would hold at that moment."""
        return np.clip(np.searchsorted(self.time, times, side="right") - 1, 0, len(self.time) - 1)


def frames_path(recording: str | Path) -> Path:
    """Where the frames of ``recording`` (``NAME.jsonl``) live: ``NAME.frames.npz`` beside it."""
    recording = Path(recording)
    return recording.with_name(recording.stem + SUFFIX)


def write_frames(path: str | Path, frames: RecordedFrames) -> Path:
    path = Path(path)
    np.savez_compressed(
        path, t=np.asarray(frames.time, dtype=np.float64),
        images=np.asarray(frames.images, dtype=np.uint8), rig=np.array(frames.rig),
    )  # fmt: skip
    return path


def read_frames(path: str | Path) -> RecordedFrames:
    """Read and check a frames file; errors name the file and the array."""
    from pydantic import ValidationError

    from retarget.motion.camera_rigs import CameraRig

    path = Path(path)
    try:
        with zipfile.ZipFile(path) as archive:
            sizes = {info.filename: info.file_size for info in archive.infolist()}
    except (OSError, zipfile.BadZipFile) as exc:
        raise MotionError(f"not a frames file (.npz): {exc}", file=path) from None
    missing = {"t.npy", "images.npy", "rig.npy"} - set(sizes)
    if missing:
        names = ", ".join(sorted(m[:-4] for m in missing))
        raise MotionError(f"frames file lacks {names} (needs t, images, rig)", file=path)
    if sizes["images.npy"] > MAX_BYTES:
        raise MotionError(
            f"images take {sizes['images.npy'] / 2**30:.1f} GiB (at most "
            f"{MAX_BYTES / 2**30:.0f} GiB read)", file=path,
        )  # fmt: skip
    try:
        with np.load(path, allow_pickle=False) as data:
            time, images, rig = data["t"], data["images"], data["rig"]
    except (OSError, ValueError) as exc:
        raise MotionError(f"cannot read frames: {exc}", file=path) from None
    if images.dtype != np.uint8 or images.ndim != 4:
        raise MotionError(
            f"'images' must be uint8 (F, C, H, W), got {images.dtype} {images.shape}", file=path
        )
    f, c, h, w = images.shape
    if not (f > 0 and 0 < c <= MAX_CAMERAS and 0 < h <= MAX_SIDE and 0 < w <= MAX_SIDE):
        raise MotionError(
            f"'images' shape {images.shape}: at least one frame, 1-{MAX_CAMERAS} cameras and "
            f"sides of at most {MAX_SIDE} pixels", file=path,
        )  # fmt: skip
    if time.shape != (f,) or time.dtype.kind not in "fi" or not np.isfinite(time).all():
        raise MotionError(f"'t' must be {f} finite seconds, one per image", file=path)
    if f > 1 and not (np.diff(time) > 0).all():
        k = int(np.flatnonzero(np.diff(time) <= 0)[0]) + 1
        raise MotionError(f"'t' is not increasing at frame {k}", file=path)
    if rig.dtype.kind != "U" or rig.shape != ():
        raise MotionError("'rig' must be one string (the camera rig as JSON)", file=path)
    try:
        parsed = CameraRig.model_validate_json(str(rig))
    except ValidationError as exc:
        raise MotionError(
            f"'rig' is not a camera rig: {exc.errors()[0]['msg']}", file=path
        ) from None
    if len(parsed.cameras) != c:
        raise MotionError(
            f"'rig' has {len(parsed.cameras)} cameras but 'images' {c} views", file=path
        )
    return RecordedFrames(time.astype(np.float64), images, parsed.model_dump_json())
