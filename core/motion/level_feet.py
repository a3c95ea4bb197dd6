"""Feet that stand flat: the sole's orientation from where the foot is planted, not from markers.

A motion file gives each foot's ankle and toe joints where its capture put them; the canonical
foot frame is then built so that its ankle-to-toe bone points at the file's toe joint. But the
line from ankle to toe joint is not the sole: Bandai Namco's toe joint sits 40 degrees below
its ankle, CMU's 13, the canonical skeleton's 21. Retargeted onto a character whose foot is a
box under the ankle, a person standing flat becomes a character on tiptoe (Bandai: the foot
pitched 19 degrees toes-down in every stance; CMU: 8 degrees toes-up), and a policy trained on
those references learns to balance on the wrong part of its foot, then falls on motion whose
feet are flat.

This module measures, per clip and per foot, the constant tilt of the foot frame while the foot
is planted (low, slow, in contact), and turns it away: the ankle's local rotation is
right-multiplied by the correction and the toe's offset and local rotation are counter-rotated,
so every joint position is unchanged (forward kinematics reproduces the file exactly, as
before) while the foot and toe frames are level whenever the person stood flat. A foot with too
few planted frames (a clip in the air, a kneel) or an implausible tilt is left as it is.

A level foot then needs the floor where its sole is. The file's ankle joint is where its
markers put it (Bandai Namco's stands 10.8 cm above the floor, CMU's 7-8 cm), while the
canonical skeleton and every character hang the sole :data:`~retarget.motion.skeleton.
ANKLE_HEIGHT_175` (in proportion) below the ankle; the tilted foot's toe reached the floor by
coincidence, a level one floats (the human 36 mm, the Dino 92 mm on Bandai Namco walks). So
the clip is also lowered (or raised) by one constant, putting its planted ankles at the
canonical ankle height: the floor is redefined by the sole model, no joint moves against
another.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from retarget.geometry import rotations as rot
from retarget.motion import skeleton as sk
from retarget.motion.clip import MotionClip

PLANTED_SPEED = 0.15  # m/s: an ankle slower than this, while in contact, is planted
PLANTED_RISE = 0.02  # m: ... and no higher than this above its lowest in the clip
MIN_FRAMES = 5  # planted frames needed to measure a foot
MAX_TILT = np.deg2rad(45.0)  # a larger constant tilt is not a marker offset: left alone
MIN_TILT = np.deg2rad(1.0)  # a foot already this level is left exactly as it is
MIN_SHIFT = 0.002  # m: a floor already this close is left exactly where it is


def level_rotation(global_rot: np.ndarray) -> np.ndarray | None:
    """The constant local correction ``C`` (wxyz) that levels frames ``(N, 4)`` of one joint:
    each ``R_t C`` keeps its heading but has its x and y axes horizontal; ``None`` when the
    mean tilt exceeds :data:`MAX_TILT` (not a flat foot)."""
    m = rot.to_matrix(global_rot)  # (N, 3, 3)
    forward = m[:, :, 0].copy()
    forward[:, 2] = 0.0
    norm = np.linalg.norm(forward, axis=-1)
    keep = norm > 1e-6
    if not keep.any():
        return None
    yaw = np.arctan2(forward[keep, 1], forward[keep, 0])
    level = rot.from_axis_angle(np.array([0.0, 0.0, 1.0]), yaw)
    c = _mean_rotation(rot.mul(rot.conj(global_rot[keep]), level))  # mean of C_t = R_t^T L_t
    return None if float(rot.angle(c)) > MAX_TILT else c


def _mean_rotation(q: np.ndarray, weights: list[float] | None = None) -> np.ndarray:
    """Weighted mean of nearby rotations ``(N, 4)``, each first put in one hemisphere."""
    q = q * np.where(q[:, :1] < 0, -1.0, 1.0)
    return rot.normalize(np.average(q, axis=0, weights=weights))


def planted(clip: MotionClip, side: int) -> np.ndarray:
    """Frames ``(T,)`` where foot ``side`` (0 left, 1 right) is down and still."""
    ankle = clip.global_pos[:, sk.FEET[side]]
    speed = np.zeros(clip.num_frames)
    if clip.num_frames > 1:
        step = np.linalg.norm(np.diff(ankle, axis=0), axis=-1) * clip.fps
        speed[1:] = step
        speed[0] = step[0]
    low = ankle[:, 2] <= ankle[:, 2].min() + PLANTED_RISE
    down = clip.contacts[:, side] if clip.contacts is not None and clip.contacts.any() else True
    return low & (speed < PLANTED_SPEED) & down


def mirrored(q: np.ndarray) -> np.ndarray:
    """A local rotation (wxyz) reflected through the body's sagittal plane (y -> -y): the
    right foot's counterpart of a left-foot correction, and back."""
    return q * np.array([1.0, -1.0, 1.0, -1.0])


def _correction(
    clip: MotionClip, joints: tuple[int, int], frames: list[np.ndarray]
) -> tuple[np.ndarray, np.ndarray] | None:
    """One correction per side for ``joints`` (left, right), measured on both feet together
    (the right one mirrored): the tilt is the capture's marker geometry, the same on both
    feet, and a foot seldom planted (a run, a hop) gets its partner's."""
    parts, weights = [], []
    for side, joint in enumerate(joints):
        if int(frames[side].sum()) < MIN_FRAMES:
            continue
        c = level_rotation(clip.global_rot[frames[side], joint])
        if c is None:
            continue
        parts.append(c if side == 0 else mirrored(c))
        weights.append(float(frames[side].sum()))
    if not parts:
        return None
    left = _mean_rotation(np.stack(parts), weights)
    return left, mirrored(left)


def level_feet(clip: MotionClip) -> MotionClip:
    """``clip`` with each foot's (and toe's) frame level where it is planted, and its planted
    ankles at the canonical ankle height; no joint moves relative to another.
    ``meta['foot_tilt_deg']`` records the tilt turned away (left, right), ``meta['floor_shift']``
    adds the vertical shift.

    Planted frames are those with both feet down and still when there are enough (a person
    standing on both feet stands flat; one foot alone may be on its ball), else each foot's.
    """
    own = [planted(clip, 0), planted(clip, 1)]
    both = own[0] & own[1]
    frames = [both, both] if int(both.sum()) >= MIN_FRAMES else own
    feet = _correction(clip, sk.FEET, frames)
    tilted = feet is not None and float(rot.angle(feet[0])) >= MIN_TILT
    shift = _ground_shift(clip, frames)
    if not tilted and abs(shift) < MIN_SHIFT:
        return clip
    local = clip.local_rot.copy()
    offsets = clip.offsets.copy()
    meta = dict(clip.meta)
    if tilted and feet is not None:
        toes = _correction(clip, sk.TOES, frames) or feet
        tilts = [0.0, 0.0]
        for side, (ankle, toe) in enumerate(zip(sk.FEET, sk.TOES, strict=True)):
            c, c_toe = feet[side], toes[side]
            local[:, ankle] = rot.normalize(rot.mul(local[:, ankle], c))
            local[:, toe] = rot.normalize(rot.mul(rot.mul(rot.conj(c), local[:, toe]), c_toe))
            offsets[toe] = rot.apply(rot.conj(c), offsets[toe])
            tilts[side] = float(np.rad2deg(rot.angle(c)))
        meta["foot_tilt_deg"] = tilts
    root = clip.root_pos
    if abs(shift) >= MIN_SHIFT:
        root = root + np.array([0.0, 0.0, shift])
        meta["floor_shift"] = float(meta.get("floor_shift", 0.0)) + shift  # type: ignore[arg-type]
        if "foot_clearance" in meta:
            meta["foot_clearance"] = np.asarray(meta["foot_clearance"]) + shift
    return clip.with_(root_pos=root, local_rot=local, offsets=offsets, meta=meta)


def _ground_shift(clip: MotionClip, frames: list[np.ndarray]) -> float:
    """Metres to add to every height so the planted ankles stand at the canonical ankle height
    of this subject; 0 without enough planted frames."""
    heights = [clip.global_pos[f, ankle, 2] for f, ankle in zip(frames, sk.FEET, strict=True)
               if int(f.sum()) >= MIN_FRAMES]  # fmt: skip
    if not heights:
        return 0.0
    target = sk.ANKLE_HEIGHT_175 * clip.height / sk.REFERENCE_HEIGHT
    return float(target - np.median(np.concatenate(heights)))


def with_level_feet(clips: Sequence[MotionClip]) -> list[MotionClip]:
    """:func:`level_feet` of every clip."""
    return [level_feet(c) for c in clips]
