"""Left/right mirroring, a free doubling of the training data.

The mirror plane is the world XZ plane (y -> -y): left and right joints swap, positions flip
their y component, and a rotation R becomes S R S with S = diag(1, -1, 1), which for a
quaternion (w, x, y, z) is (w, -x, y, -z).
"""

from __future__ import annotations

import numpy as np

from retarget.motion import skeleton as sk
from retarget.motion.clip import MotionClip

_FLIP_POS = np.array([1.0, -1.0, 1.0])
_FLIP_QUAT = np.array([1.0, -1.0, 1.0, -1.0])


def mirror_quat(q: np.ndarray) -> np.ndarray:
    """World-frame reflection of rotations through the XZ plane."""
    return q * _FLIP_QUAT


def mirror(clip: MotionClip) -> MotionClip:
    """The clip reflected through the XZ plane with left and right swapped."""
    perm = np.array(sk.LEFT_RIGHT)
    meta = dict(clip.meta)
    if "foot_clearance" in meta:
        meta["foot_clearance"] = np.asarray(meta["foot_clearance"])[..., ::-1]
    return clip.with_(
        root_pos=clip.root_pos * _FLIP_POS,
        local_rot=mirror_quat(clip.local_rot[:, perm]),
        offsets=clip.offsets[perm] * _FLIP_POS,
        contacts=clip.contacts[:, ::-1] if clip.contacts is not None else None,
        name=f"{clip.name}_mirrored" if clip.name else "mirrored",
        meta=meta,
    )
