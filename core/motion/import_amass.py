"""AMASS (SMPL, SMPL-H, SMPL-X ``.npz``) -> canonical, floor-aligned, contact-labelled clips.

AMASS stores per frame the axis-angle rotations of the body model's joints (``poses``: the
root's global rotation, then each joint's local one; 24, 52 or 55 joints), the model's
translation (``trans``), the subject's shape (``betas``) and the capture rate
(``mocap_framerate`` in SMPL-H files, ``mocap_frame_rate`` in SMPL-X ones). The first 22 joints
of all three models are SMPL's body, with the same tree as the canonical skeleton, so the
rotations map one to one after a change of rest frame: SMPL's T-pose faces +Z with +Y up and
+X to the body's left; the canonical one faces +X, Z up, +Y left (``C`` below).

Bone lengths: with the user's own body model (``model``: a directory holding
``{neutral,male,female}/model.npz``, SMPL-H's distribution layout, read without pickle; never
shipped with the project) the joints come from the subject's betas through the model's joint
regressor. Without it the canonical skeleton's average adult proportions are used, scaled to
the mean AMASS subject's 1.70 m (:data:`MEAN_HEIGHT`), and the pelvis is placed at
``trans + MEAN_PELVIS``, the neutral model's approximate pelvis joint.
"""

from __future__ import annotations

import zipfile
from pathlib import Path

import numpy as np

from retarget.errors import MotionError
from retarget.geometry import rotations as rot
from retarget.motion import skeleton as sk
from retarget.motion.canonicalize import up_axis_matrix
from retarget.motion.clip import MotionClip
from retarget.motion.contacts import label_contacts
from retarget.motion.floor import align_floor, foot_points
from retarget.motion.plausible import check_plausible

SMPL_OF_CANONICAL = (0, 1, 4, 7, 10, 2, 5, 8, 11, 3, 6, 9, 12, 15, 13, 16, 18, 20, 14, 17, 19, 21)
"""SMPL body joint index of each canonical joint (canonical order)."""
SMPL_PARENTS = (-1, 0, 0, 0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 9, 9, 12, 13, 14, 16, 17, 18, 19)
C = np.array([[0.0, 1.0, 0.0], [0.0, 0.0, 1.0], [1.0, 0.0, 0.0]])
"""Canonical rest axes in SMPL's rest frame (columns: forward, left, up = SMPL z, x, y)."""
MEAN_HEIGHT = 1.70
MEAN_PELVIS = np.array([0.0, -0.22, 0.03])
"""Approximate pelvis joint of the neutral model at rest (model frame, metres)."""
MAX_FRAMES = 2_000_000
MAX_FILE_BYTES = 4 * 2**30


def _scalar(data, keys: tuple[str, ...]) -> float | None:
    for key in keys:
        if key in data:
            value = np.asarray(data[key])
            if value.size == 1 and value.dtype.kind in "fiu":
                return float(value.reshape(()))
    return None


def model_joints(model_dir: Path, gender: str, betas: np.ndarray) -> np.ndarray:
    """The subject's rest joints ``(22, 3)`` (model frame) from a body model ``.npz``."""
    path = model_dir / gender / "model.npz"
    if not path.is_file():
        path = model_dir / "neutral" / "model.npz"
    try:
        with np.load(path, allow_pickle=False) as model:
            template = np.asarray(model["v_template"], dtype=np.float64)
            dirs = np.asarray(model["shapedirs"], dtype=np.float64)
            regressor = np.asarray(model["J_regressor"], dtype=np.float64)
    except (OSError, KeyError, ValueError) as exc:
        raise MotionError(f"cannot read the body model (v_template, shapedirs, J_regressor): "
                          f"{exc}", file=path) from None  # fmt: skip
    k = min(len(betas), dirs.shape[-1])
    verts = template + dirs[..., :k] @ betas[:k]
    return (regressor @ verts)[:22]


def load_amass(
    path: str | Path, *, model: str | Path | None = None, up: str = "+z",
    fps: float | None = None,
) -> MotionClip:  # fmt: skip
    """Read an AMASS ``.npz`` (see the module docstring)."""
    path = Path(path)
    file = str(path)
    try:
        if path.stat().st_size > MAX_FILE_BYTES:
            raise MotionError("file is larger than 4 GiB", file=file)
        with np.load(path, allow_pickle=False) as data:
            missing = [k for k in ("poses", "trans") if k not in data]
            if missing:
                raise MotionError(
                    f"not an AMASS file: no {' or '.join(missing)} (has "
                    f"{', '.join(data.files) or 'nothing'})", file=file,
                )  # fmt: skip
            poses = np.asarray(data["poses"], dtype=np.float64)
            trans = np.asarray(data["trans"], dtype=np.float64)
            betas = np.asarray(data["betas"], dtype=np.float64).ravel() if "betas" in data \
                else np.zeros(0)  # fmt: skip
            rate = _scalar(data, ("mocap_framerate", "mocap_frame_rate"))
            gender = str(np.asarray(data["gender"]).reshape(())) if "gender" in data \
                else "neutral"  # fmt: skip
    except (OSError, ValueError, TypeError, EOFError, zipfile.BadZipFile) as exc:
        raise MotionError(f"cannot read AMASS file: {exc}", file=file) from None
    rate = fps if fps is not None else rate
    if rate is None:
        raise MotionError("no frame rate (mocap_framerate / mocap_frame_rate)", file=file,
                          hint="give the format's fps")  # fmt: skip
    t = poses.shape[0] if poses.ndim == 2 else 0
    if poses.ndim != 2 or poses.shape[1] < 66 or poses.shape[1] % 3:
        raise MotionError(f"'poses' must be (frames, 3 x joints) with >= 22 joints, got "
                          f"{poses.shape}", file=file)  # fmt: skip
    if trans.shape != (t, 3):
        raise MotionError(f"'trans' must be ({t}, 3), got {trans.shape}", file=file)
    if not 2 <= t <= MAX_FRAMES or not 0 < rate <= 1000:
        raise MotionError(f"{t} frames at {rate} Hz: need 2-{MAX_FRAMES} frames, 0-1000 Hz",
                          file=file)  # fmt: skip
    if not (np.isfinite(poses[:, :66]).all() and np.isfinite(trans).all()):
        raise MotionError("'poses' or 'trans' has non-finite values", file=file)
    gender = gender.lower() if gender.lower() in ("male", "female", "neutral") else "neutral"

    world = up_axis_matrix(up)
    aa = poses[:, :66].reshape(t, 22, 3)
    angle = np.linalg.norm(aa, axis=-1)
    axis = aa / np.maximum(angle, 1e-12)[..., None]
    local_smpl = rot.to_matrix(rot.from_axis_angle(axis, angle))  # (T, 22, 3, 3)
    local = np.empty_like(local_smpl)
    local[:, 0] = world @ local_smpl[:, 0] @ C  # root: global rotation, canonical rest frame
    local[:, 1:] = C.T @ local_smpl[:, 1:] @ C

    if model is not None:
        joints = model_joints(Path(model), gender, betas)
        pelvis = joints[0]
        offsets_smpl = joints - joints[list(SMPL_PARENTS)]
        offsets = np.zeros((sk.NUM_JOINTS, 3))
        for j in range(1, sk.NUM_JOINTS):
            offsets[j] = C.T @ offsets_smpl[SMPL_OF_CANONICAL[j]]
    else:
        pelvis = MEAN_PELVIS
        offsets = sk.rest_offsets(MEAN_HEIGHT)
    canonical_local = local[:, list(SMPL_OF_CANONICAL)]
    root_pos = (trans + pelvis) @ world.T
    clip = MotionClip(fps=rate, root_pos=root_pos,
                      local_rot=rot.normalize(rot.from_matrix(canonical_local)),
                      offsets=offsets, name=path.stem)  # fmt: skip
    clip = align_floor(clip)
    contacts = label_contacts(foot_points(clip), clip.meta["foot_clearance"], clip.fps)  # type: ignore[arg-type]
    meta = {**clip.meta, "up": up, "gender": gender, "body_model": str(model) if model else None}
    clip = clip.with_(contacts=contacts, skeleton="smpl", meta=meta, source=path)
    return check_plausible(clip, path)
