"""Rotations from joint positions alone: a canonical clip fitted to position-only captures.

Markerless capture, video pose estimation and many mocap exports give joint positions and no
bone rotations. Each canonical joint's global rotation is built from two directions measured
in the data and their T-pose counterparts (a triad, exact for the first, closest for the
second):

* the **bone** to its child (the primary direction: so forward kinematics reproduces every
  single-child joint's position exactly);
* a **twist** reference: the hip line for the pelvis (left hip minus right hip), the shoulder
  line for the upper spine, blended from hips to shoulders up the spine; for a limb (upper
  arm, thigh) the normal of the plane of its chain (elbow and knee are hinges, so the forearm
  and shin share that axis), and the leg's axis for the foot.

A limb's bend plane is undefined when it is straight: there the axis is held from the nearest
frames where it is well defined (in the parent's frame, weighted by how bent the limb is), and
smoothed over time, so the twist does not flip. Joints without a child (head, wrists, toes)
keep their parent's rotation (no local rotation) unless a hand or foot tip is given. Offsets
(bone vectors in the parent's frame) are the mean over frames, so a non-rigid capture is
fitted as the closest rigid skeleton.
"""

from __future__ import annotations

import numpy as np

from retarget.geometry import rotations as rot
from retarget.motion import skeleton as sk
from retarget.motion.clip import MotionClip, local_from_global

_J = {n: i for i, n in enumerate(sk.JOINT_NAMES)}
MIN_BEND = np.sin(np.radians(15.0))
"""A limb bent less than this (sine of the angle) has an ill-defined bend plane."""
SMOOTH_FRAMES = 2.0
"""Standard deviation, in frames, of the temporal smoothing of twist axes."""


def _unit(v: np.ndarray) -> np.ndarray:
    return v / np.maximum(np.linalg.norm(v, axis=-1, keepdims=True), 1e-9)


def _triad(primary: np.ndarray, secondary: np.ndarray, p0: np.ndarray, s0: np.ndarray):
    """Rotations ``(T, 3, 3)`` taking the rest pair (``p0``, ``s0``) onto the measured pair
    (``primary`` exactly, ``secondary`` as closely as orthogonality allows)."""
    def frame(p, s):
        a = _unit(p)
        b = _unit(s - (s * a).sum(-1, keepdims=True) * a)
        return np.stack([a, b, np.cross(a, b)], axis=-1)

    rest = frame(np.broadcast_to(p0, primary.shape), np.broadcast_to(s0, primary.shape))
    return frame(primary, secondary) @ np.swapaxes(rest, -1, -2)


def _smooth(v: np.ndarray, weight: np.ndarray, fallback: np.ndarray) -> np.ndarray:
    """Unit vectors ``(T, 3)`` where each frame is the weight-averaged neighbourhood of
    ``v`` (Gaussian over time); frames with no weight nearby take the nearest well-weighted
    frame's value, or ``fallback`` when there is none."""
    t = len(v)
    good = weight > 0.5
    if not good.any():
        return np.broadcast_to(_unit(fallback), v.shape).copy()
    idx = np.arange(t)
    last = np.maximum.accumulate(np.where(good, idx, -1))
    nxt = np.minimum.accumulate(np.where(good, idx, t)[::-1])[::-1]
    near = np.where(last < 0, nxt, np.where(nxt >= t, last,
                    np.where(idx - last <= nxt - idx, last, nxt)))  # fmt: skip
    held = weight[:, None] * v + (1 - weight[:, None]) * v[near]
    radius = int(3 * SMOOTH_FRAMES)
    kernel = np.exp(-0.5 * (np.arange(-radius, radius + 1) / SMOOTH_FRAMES) ** 2)
    padded = np.pad(held * (0.1 + weight[:, None]), ((radius, radius), (0, 0)), mode="edge")
    out = np.stack([np.convolve(padded[:, k], kernel, mode="valid") for k in range(3)], -1)
    return _unit(out)


def _limb_axis(
    top: np.ndarray, mid: np.ndarray, end: np.ndarray, parent: np.ndarray, rest_axis: np.ndarray
) -> np.ndarray:
    """The hinge axis ``(T, 3)`` of a two-bone chain (world), normal to its plane, oriented
    so that the bend is a positive rotation; held and smoothed in the ``parent`` frame."""
    upper, lower = mid - top, end - mid
    normal = np.cross(_unit(upper), _unit(lower))
    size = np.linalg.norm(normal, axis=-1)
    weight = np.clip(size / MIN_BEND, 0.0, 1.0) ** 2
    local = np.einsum("tki,tk->ti", parent, _unit(normal))  # in the parent's frame
    local = _smooth(local, weight, rest_axis)
    return np.einsum("tij,tj->ti", parent, local)


def fit_rotations(pos: np.ndarray, tips: dict[str, np.ndarray] | None = None) -> np.ndarray:
    """Global rotation matrices ``(T, J, 3, 3)`` of canonical joint positions ``(T, J, 3)``
    (metres, Z up). ``tips``: optional extra points, ``left_hand``/``right_hand`` (a point
    along the hand, e.g. the middle finger's base), which give the wrists a rotation."""
    tips = tips or {}
    t = pos.shape[0]
    g = np.broadcast_to(np.eye(3), (t, sk.NUM_JOINTS, 3, 3)).copy()
    off = sk.rest_offsets()
    p = {n: pos[:, i] for n, i in _J.items()}
    _, y, z = np.eye(3)
    hips = p["left_hip"] - p["right_hip"]
    shoulders = p["left_shoulder"] - p["right_shoulder"]
    g[:, _J["pelvis"]] = _triad(p["spine"] - p["pelvis"], hips, z, y)
    for name, child, w in (("spine", "spine1", 1 / 3), ("spine1", "spine2", 2 / 3)):
        g[:, _J[name]] = _triad(p[child] - p[name], (1 - w) * _unit(hips) + w * _unit(shoulders),
                                off[_J[child]], y)  # fmt: skip
    collars = p["left_collar"] - p["right_collar"]
    g[:, _J["spine2"]] = _triad(p["neck"] - p["spine2"], collars, z, y)
    g[:, _J["neck"]] = _triad(p["head"] - p["neck"], shoulders, z, y)
    g[:, _J["head"]] = g[:, _J["neck"]]
    for side, sign in (("left", 1.0), ("right", -1.0)):
        collar, shoulder, elbow, wrist = (f"{side}_{n}" for n in ("collar", "shoulder", "elbow",
                                                                   "wrist"))  # fmt: skip
        chest = g[:, _J["spine2"]]
        g[:, _J[collar]] = _triad(p[shoulder] - p[collar], chest[..., 2], sign * y, z)
        # T-pose arm along +-y; the elbow bends the forearm forward (+x): axis d x b = -+z
        arm_axis = _limb_axis(p[shoulder], p[elbow], p[wrist], g[:, _J[collar]], -sign * z)
        g[:, _J[shoulder]] = _triad(p[elbow] - p[shoulder], arm_axis, sign * y, -sign * z)
        g[:, _J[elbow]] = _triad(p[wrist] - p[elbow], arm_axis, sign * y, -sign * z)
        if side + "_hand" in tips:
            g[:, _J[wrist]] = _triad(tips[side + "_hand"] - p[wrist], arm_axis, sign * y,
                                     -sign * z)  # fmt: skip
        else:
            g[:, _J[wrist]] = g[:, _J[elbow]]
        hip, knee, ankle, toe = (f"{side}_{n}" for n in ("hip", "knee", "ankle", "toe"))
        # legs hang along -z; the knee bends the shin backwards (-x): axis d x b = +y
        leg_axis = _limb_axis(p[hip], p[knee], p[ankle], g[:, _J["pelvis"]], y)
        g[:, _J[hip]] = _triad(p[knee] - p[hip], leg_axis, -z, y)
        g[:, _J[knee]] = _triad(p[ankle] - p[knee], leg_axis, -z, y)
        g[:, _J[ankle]] = _triad(p[toe] - p[ankle], leg_axis, off[_J[toe]], y)
        g[:, _J[toe]] = g[:, _J[ankle]]
    return g


def clip_from_positions(
    pos: np.ndarray, fps: float, tips: dict[str, np.ndarray] | None = None, name: str = ""
) -> MotionClip:
    """A canonical clip (not floor-aligned) reproducing joint positions ``(T, J, 3)``."""
    gmat = fit_rotations(pos, tips)
    local = local_from_global(rot.from_matrix(gmat))
    offsets = np.zeros((sk.NUM_JOINTS, 3))
    for j in range(1, sk.NUM_JOINTS):
        pj = sk.PARENTS[j]
        v = np.einsum("tki,tk->ti", gmat[:, pj], pos[:, j] - pos[:, pj])
        offsets[j] = v.mean(0)
    return MotionClip(fps=fps, root_pos=pos[:, 0].copy(), local_rot=local, offsets=offsets,
                      name=name)  # fmt: skip
