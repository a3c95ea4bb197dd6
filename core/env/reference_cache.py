"""The kinematic reference of a motion library cached on disk by content.

Retargeting every frame of a corpus onto a character, its joint torques and forward
kinematics over it cost about 33 s per hour of motion (8 s of it the torques); they depend
only on the compiled model, the joint map, the clips (at the control rate), the contact
margin and the scene's mocap placements, so the result is stored under the hash of exactly
those as an ``.npz`` of plain arrays (read back with ``allow_pickle=False``, so a cache file
runs no code). Small libraries (tests, a handful of clips) are not worth a file and are
always computed.
"""

from __future__ import annotations

import hashlib
import os
import tempfile
from collections.abc import Sequence
from pathlib import Path

import mujoco
import numpy as np

from retarget.motion.clip import MotionClip
from retarget.motion.clip_cache import clip_cache_dir

VERSION = 2
"""Bumped when the reference is computed differently, so old files are not reused."""
MIN_FRAMES = 20_000
"""Libraries shorter than this (about 9 minutes at 36 Hz) are computed, not cached."""
FIELDS = ("qpos", "qvel", "labels", "joint_torque", "body_pos", "body_quat", "body_linvel",
          "body_angvel", "site_pos", "site_quat")  # fmt: skip


def reference_key(
    model: mujoco.MjModel,
    joint_map: object,
    clips: Sequence[MotionClip],
    margin: float,
    mocap: Sequence[tuple[np.ndarray, np.ndarray] | None] | None,
    ground: bool = False,
) -> str | None:
    """Hash of everything the reference depends on, or None when it is not worth caching.
    (``ground`` adds the clips' foot contact labels, which grounding reads; keys without it
    are those of references cached before it existed.)"""
    if sum(c.num_frames for c in clips) < MIN_FRAMES or clip_cache_dir() is None:
        return None
    h = hashlib.sha256(f"v{VERSION} {margin!r} ".encode())
    if ground:
        h.update(b"ground ")
        for clip in clips:
            h.update(np.ascontiguousarray(clip.contacts, dtype=bool).tobytes())
    buffer = np.zeros(mujoco.mj_sizeModel(model), dtype=np.uint8)
    mujoco.mj_saveModel(model, None, buffer)
    h.update(hashlib.sha256(buffer.tobytes()).digest())
    h.update(repr(joint_map).encode())
    for clip in clips:
        h.update(f"{clip.fps!r} {clip.num_frames} ".encode())
        for array in (clip.root_pos, clip.local_rot, clip.offsets):
            h.update(np.ascontiguousarray(array, dtype=np.float64).tobytes())
    for placement in mocap or ():
        for array in placement or ():
            h.update(np.ascontiguousarray(array, dtype=np.float64).tobytes())
    return h.hexdigest()[:40]


def _path(key: str) -> Path:
    folder = clip_cache_dir()
    assert folder is not None
    return folder.parent / "reference" / f"{key}.npz"


def load_reference(key: str | None) -> dict[str, np.ndarray] | None:
    """The cached arrays, or None (no key, no file, or an unreadable one)."""
    if key is None or not _path(key).exists():
        return None
    try:
        with np.load(_path(key), allow_pickle=False) as z:
            return {name: z[name] for name in FIELDS}
    except (OSError, ValueError, KeyError):
        return None


def store_reference(key: str | None, arrays: dict[str, np.ndarray]) -> None:
    """Write the arrays atomically; a full disk only skips caching."""
    if key is None:
        return
    path = _path(key)
    tmp = None
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=".ref.", suffix=".npz")
        with os.fdopen(fd, "wb") as handle:
            np.savez(handle, **{name: arrays[name] for name in FIELDS})
        os.replace(tmp, path)
    except OSError:
        if tmp is not None:
            Path(tmp).unlink(missing_ok=True)
