"""Resampling a clip to another frame rate (the control rate), with slerp for rotations.

Training steps the simulation at a fixed control rate (36 Hz by default), so reference frames
must exist at exactly those instants; interpolating once per clip at load time keeps the
per-step lookup a plain index.
"""

from __future__ import annotations

import numpy as np

from retarget.geometry import rotations as rot
from retarget.motion.clip import MotionClip

CONTROL_RATE = 36.0


def resample(clip: MotionClip, fps: float = CONTROL_RATE) -> MotionClip:
    """The clip at ``fps`` over the same duration (root linear, rotations slerp)."""
    if fps <= 0:
        raise ValueError(f"fps must be positive, got {fps}")
    if abs(fps - clip.fps) < 1e-9:
        return clip
    count = int(np.floor(clip.duration * fps + 1e-9)) + 1
    return at_frames(clip, np.arange(count) / fps * clip.fps, fps)


def at_frames(clip: MotionClip, src: np.ndarray, fps: float | None = None) -> MotionClip:
    """A clip whose frame ``i`` is ``clip`` at fractional frame ``src[i]`` (root linear,
    rotations slerp, contacts of the nearest frame), played at ``fps`` (default: the clip's).

    Any monotone or non-monotone time map works, so one routine serves both resampling and
    time-warping (slowing a clip to a standstill)."""
    n = clip.num_frames
    src = np.clip(np.asarray(src, dtype=np.float64), 0.0, n - 1)
    i0 = np.clip(np.floor(src).astype(np.int64), 0, max(n - 2, 0))
    i1 = np.minimum(i0 + 1, n - 1)
    a = np.clip(src - i0, 0.0, 1.0)
    root = clip.root_pos[i0] * (1 - a)[:, None] + clip.root_pos[i1] * a[:, None]
    local = rot.slerp(clip.local_rot[i0], clip.local_rot[i1], a[:, None])
    nearest = np.clip(np.rint(src).astype(np.int64), 0, n - 1)
    contacts = clip.contacts[nearest] if clip.contacts is not None else None
    return clip.with_(fps=float(fps or clip.fps), root_pos=root, local_rot=local,
                      contacts=contacts)  # fmt: skip
