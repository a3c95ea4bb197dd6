"""Writing a canonical clip as an AMASS-style SMPL-H ``.npz`` (the inverse of
:mod:`retarget.motion.import_amass`): for samples and round-trip tests, and for handing
clips to SMPL-based tools. Hands and the model's extra joints are left at rest."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from retarget.geometry import rotations as rot
from retarget.motion.clip import MotionClip
from retarget.motion.import_amass import MEAN_PELVIS, SMPL_OF_CANONICAL, C
from retarget.motion.resample import resample

SMPLH_JOINTS = 52


def amass_arrays(clip: MotionClip) -> dict[str, np.ndarray]:
    """``poses`` ``(T, 156)`` axis-angle, ``trans`` ``(T, 3)`` (Z-up world, mean pelvis)."""
    t = clip.num_frames
    local = rot.to_matrix(clip.local_rot)  # canonical order
    smpl = np.broadcast_to(np.eye(3), (t, SMPLH_JOINTS, 3, 3)).copy()
    for j, s in enumerate(SMPL_OF_CANONICAL):
        smpl[:, s] = local[:, j] @ C.T if j == 0 else C @ local[:, j] @ C.T
    q = rot.from_matrix(smpl)
    angle = 2 * np.arctan2(np.linalg.norm(q[..., 1:], axis=-1), q[..., 0])
    axis = q[..., 1:] / np.maximum(np.linalg.norm(q[..., 1:], axis=-1, keepdims=True), 1e-12)
    poses = (axis * angle[..., None]).reshape(t, -1)
    return {"poses": poses, "trans": clip.root_pos - MEAN_PELVIS}


def write_amass(clip: MotionClip, path: str | Path, *, fps: float = 120.0,
                seconds: float | None = None) -> Path:  # fmt: skip
    """Write ``clip`` resampled to ``fps`` (the first ``seconds`` when given)."""
    clip = resample(clip, fps)
    arrays = amass_arrays(clip)
    if seconds is not None:
        n = max(2, int(seconds * fps))
        arrays = {k: v[:n] for k, v in arrays.items()}
    path = Path(path)
    np.savez(path, **arrays, betas=np.zeros(16), gender=np.array("neutral"),
             mocap_framerate=np.array(fps))  # fmt: skip
    return path
