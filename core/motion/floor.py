"""Floor alignment: put the ground under the feet, and model where the soles are.

No source marks the sole, so the foot is modelled by three points per side: the ankle joint
(heel), the toe joint (ball of the foot) and a toe tip :data:`TOE_TIP` ahead of the toe joint
(needed for tiptoe steps, where heel and ball are both lifted). Each point gets a *clearance*:
its typical height when it carries weight (the 5th percentile of its height over the clip).
The lowest sole point of a frame is ``min_k(z_k - clearance_k)``, which is ~0 whenever a foot
is planted. The floor is put at the toe tips' clearance.
"""

from __future__ import annotations

import numpy as np

from retarget.geometry import rotations as rot
from retarget.motion import skeleton as sk
from retarget.motion.clip import MotionClip

TOE_TIP = (0.05, 0.0, -0.02)
"""Toe joint (ball of the foot) to toe tip in the toe's frame for a 1.75 m adult, metres: with
the foot flat the toe joint is 2 cm above the ground and the tip touches it."""
CLEARANCE_PERCENTILE = 5.0


def foot_points(clip: MotionClip) -> np.ndarray:
    """Positions ``(T, 3 [heel, ball, tip], 2 [left, right], 3)`` of the sole model points."""
    g = clip.global_pos
    toes = np.array(sk.TOES)
    tip = g[:, toes] + rot.apply(
        clip.global_rot[:, toes], np.array(TOE_TIP) * clip.height / sk.REFERENCE_HEIGHT
    )
    return np.stack([g[:, np.array(sk.FEET)], g[:, toes], tip], axis=1)


def clearances(points: np.ndarray) -> np.ndarray:
    """Per sole point, its height when weight-bearing ``(3, 2)``."""
    return np.percentile(points[..., 2], CLEARANCE_PERCENTILE, axis=0)


def sole_heights(points: np.ndarray, clearance: np.ndarray) -> np.ndarray:
    """Per frame and foot (left, right), the lowest sole point above the floor ``(T, 2)``."""
    return (points[..., 2] - clearance).min(axis=1)


def align_floor(clip: MotionClip) -> MotionClip:
    """Shift the clip vertically so the floor is z = 0; stores ``foot_clearance`` in meta."""
    clear = clearances(foot_points(clip))
    floor = float(clear[2].min())
    root = clip.root_pos.copy()
    root[:, 2] -= floor
    meta = dict(clip.meta)
    meta["foot_clearance"] = clear - floor
    meta["floor_shift"] = -floor
    return clip.with_(root_pos=root, meta=meta)
