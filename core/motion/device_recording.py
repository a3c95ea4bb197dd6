"""Recorded device streams: one file format and the OpenXR / Unity coordinate conventions.

**Format** (``.jsonl``, UTF-8, one JSON object per line). The first line is a header::

    {"format": "retarget-devices", "version": 1, "convention": "retarget"}

Camera frames, when the headset's cameras were recorded too, are a separate file beside it
(``NAME.frames.npz``, :mod:`retarget.motion.device_frames`) on the same clock.

``convention`` says how the poses in the file are expressed (see below). Every further line
is one sample::

    {"t": 0.0133, "hmd": [x, y, z, qw, qx, qy, qz], "left": [...], "right": [...]}

``t`` is seconds (strictly increasing), positions metres, quaternions ``wxyz`` in every
convention (Unity's own API writes ``xyzw``: reorder when exporting). A device that was not
tracked in a sample is ``null``; readers hold its last pose and report it untracked.

**Conventions.** ``retarget``: right-handed, Z up, X forward, Y left (the project's frame;
devices point along +X). ``openxr``: right-handed, Y up, -Z forward, +X right (reference and
device spaces alike). ``unity``: left-handed, Y up, +Z forward, +X right. A pose converts by
``p' = M p`` and ``R' = M R M^T`` with the constant axis matrix below, which maps world *and*
device axes consistently (so "looking forward" stays identity in every convention).
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from retarget.errors import MotionError
from retarget.geometry import rotations as rot
from retarget.motion.device_frames import RecordedFrames, frames_path, read_frames, write_frames
from retarget.motion.devices import DEVICES

FORMAT = "retarget-devices"
VERSION = 1

# rows: retarget axes expressed in the other convention's coordinates (retarget = M @ other)
TO_RETARGET: dict[str, np.ndarray] = {
    "retarget": np.eye(3),
    "openxr": np.array([[0.0, 0.0, -1.0], [-1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]),
    "unity": np.array([[0.0, 0.0, 1.0], [-1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]),
}


def convert(poses: np.ndarray, source: str, target: str) -> np.ndarray:
    """Convert poses ``(..., 7)`` between conventions (``retarget``, ``openxr``, ``unity``)."""
    for name in (source, target):
        if name not in TO_RETARGET:
            raise ValueError(f"unknown convention {name!r}; known: {', '.join(TO_RETARGET)}")
    m = TO_RETARGET[target].T @ TO_RETARGET[source]
    poses = np.asarray(poses, dtype=np.float64)
    pos = poses[..., :3] @ m.T
    mat = m @ rot.to_matrix(poses[..., 3:]) @ m.T
    return np.concatenate([pos, rot.from_matrix(mat)], axis=-1)


MAX_SECONDS = 3 * 3600.0
"""Longest recording read, seconds (it is resampled to the control rate)."""
MAX_GAP = 10.0
"""Longest gap between two samples, seconds: a headset streams at 72-120 Hz."""
MAX_DISTANCE = 100.0
"""Farthest a device may be from the origin, metres (a room-scale or walking session)."""


@dataclass
class DeviceRecording:
    """A device stream in the retarget convention."""

    time: np.ndarray  # (T,) seconds
    poses: np.ndarray  # (T, 3, 7)
    tracked: np.ndarray  # (T, 3) bool
    frames: RecordedFrames | None = None  # the headset cameras' images, when recorded


def write_recording(path: str | Path, rec: DeviceRecording, convention: str = "retarget") -> Path:
    path = Path(path)
    poses = convert(rec.poses, "retarget", convention)
    lines = [json.dumps({"format": FORMAT, "version": VERSION, "convention": convention})]
    for k in range(rec.time.shape[0]):
        sample: dict[str, object] = {"t": float(rec.time[k])}
        for d, name in enumerate(DEVICES):
            sample[name] = [round(float(v), 7) for v in poses[k, d]] if rec.tracked[k, d] else None
        lines.append(json.dumps(sample))
    path.write_text("\n".join(lines) + "\n")
    if rec.frames is not None:
        write_frames(frames_path(path), rec.frames)
    return path


def parse_sample(
    obj: dict, path: str | Path | None = None, line: int | None = None
) -> tuple[float, np.ndarray, np.ndarray]:
    """One sample ``{"t": .., "hmd": [7] | null, "left": .., "right": ..}`` as its time, poses
    ``(3, 7)`` (as given, in the sample's convention; identity where untracked) and tracked
    flags ``(3,)``; a malformed one raises :class:`MotionError` naming the file and line. The
    recording reader and the live server (:mod:`retarget.live`) read samples through this."""
    t = obj.get("t")
    if isinstance(t, bool) or not isinstance(t, int | float) or not math.isfinite(t):
        raise MotionError("sample needs a finite time 't' in seconds", file=path, line=line)
    poses = np.zeros((len(DEVICES), 7))
    poses[:, 3] = 1.0
    tracked = np.zeros(len(DEVICES), dtype=bool)
    for d, name in enumerate(DEVICES):
        value = obj.get(name)
        if value is None:
            continue
        if (
            not isinstance(value, list)
            or len(value) != 7
            or not all(
                isinstance(v, int | float) and not isinstance(v, bool) and math.isfinite(v)
                for v in value
            )
        ):
            raise MotionError(
                f"'{name}' must be 7 finite numbers [x, y, z, qw, qx, qy, qz] or null",
                file=path, line=line,
            )  # fmt: skip
        if max(abs(v) for v in value[:3]) > MAX_DISTANCE:
            raise MotionError(
                f"'{name}' is {max(abs(v) for v in value[:3]):.0f} m from the origin; devices "
                f"are at most {MAX_DISTANCE:.0f} m away (units in metres?)",
                file=path, line=line,
            )  # fmt: skip
        q = np.array(value[3:], dtype=np.float64)
        if not 0.5 < np.linalg.norm(q) < 1.5:
            raise MotionError(f"'{name}' quaternion is not unit length", file=path, line=line)
        poses[d] = np.concatenate([value[:3], rot.normalize(q)])
        tracked[d] = True
    return float(t), poses, tracked


def read_recording(path: str | Path) -> DeviceRecording:
    """Read a ``.jsonl`` device recording into the retarget convention (errors name the line),
    with its camera frames when ``NAME.frames.npz`` is beside it."""
    path = Path(path)
    try:
        text = path.read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError) as exc:
        raise MotionError(f"cannot read device recording: {exc}", file=path) from None
    lines = [(i + 1, line) for i, line in enumerate(text.splitlines()) if line.strip()]
    if not lines:
        raise MotionError("device recording is empty", file=path, line=1)

    def load(number: int, line: str) -> dict:
        try:
            obj = json.loads(line)
        except json.JSONDecodeError as exc:
            raise MotionError(f"not JSON: {exc.msg}", file=path, line=number) from None
        if not isinstance(obj, dict):
            raise MotionError("each line must be a JSON object", file=path, line=number)
        return obj

    header = load(*lines[0])
    if header.get("format") != FORMAT or header.get("version") != VERSION:
        raise MotionError(
            f"header must be {{'format': '{FORMAT}', 'version': {VERSION}, ...}}",
            file=path,
            line=lines[0][0],
        )
    convention = header.get("convention", "retarget")
    if convention not in TO_RETARGET:
        raise MotionError(
            f"unknown convention {convention!r}; known: {', '.join(TO_RETARGET)}",
            file=path,
            line=lines[0][0],
        )
    count = len(lines) - 1
    if count == 0:
        raise MotionError("device recording has no samples", file=path, line=lines[0][0])
    time = np.empty(count)
    poses = np.zeros((count, 3, 7))
    poses[..., 3] = 1.0
    tracked = np.zeros((count, 3), dtype=bool)
    for k, (number, line) in enumerate(lines[1:]):
        t, pose, seen = parse_sample(load(number, line), path, number)
        if k and t <= time[k - 1]:
            raise MotionError(
                f"time {t} is not after the previous sample's {time[k - 1]}", file=path, line=number
            )
        if k and t - time[k - 1] > MAX_GAP:
            raise MotionError(
                f"{t - time[k - 1]:.1f} s since the previous sample; samples are at most "
                f"{MAX_GAP:.0f} s apart",
                file=path, line=number,
            )  # fmt: skip
        if k and t - time[0] > MAX_SECONDS:
            raise MotionError(
                f"the recording is longer than {MAX_SECONDS / 3600:.0f} h", file=path, line=number
            )
        time[k] = t
        for d in range(len(DEVICES)):
            poses[k, d] = pose[d] if seen[d] else (poses[k - 1, d] if k else poses[k, d])
        tracked[k] = seen
    if not tracked.any():
        raise MotionError("no device is tracked in any sample (every pose is null)", file=path)
    poses = convert(poses, convention, "retarget")
    frames = None
    if frames_path(path).exists():
        frames = read_frames(frames_path(path))
        if frames.time[-1] < time[0] or frames.time[0] > time[-1]:
            raise MotionError(
                f"the frames span {frames.time[0]:.2f}-{frames.time[-1]:.2f} s but the poses "
                f"{time[0]:.2f}-{time[-1]:.2f} s: they must share one clock",
                file=frames_path(path),
            )
    return DeviceRecording(time, poses, tracked, frames)
