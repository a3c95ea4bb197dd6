"""Whether a body could follow a reference at all: its centre of mass may not fall faster
than gravity.

Contacts push and friction drags, but nothing pulls a body down harder than gravity does; a
reference whose centre of mass accelerates downward by more than ``g`` asks for what no
controller can give, and a tracker's error on those frames says nothing about the tracker.
Retargeting to a larger body scales every length and keeps the person's timing, so every
acceleration grows with the scale: a person's run played by the 2.5 m Dino (1.43 times a
1.75 m person) asks its centre of mass to fall at up to 1.9 g, where the same run on the
human asks for 1.4 g (mocap's own noise) and a walk for a quarter of g. The share of such
frames is reported beside an expert's errors (``reference_over_gravity`` in its report) so a
researcher can tell a hard planner problem from an impossible reference.
"""

from __future__ import annotations

import mujoco
import numpy as np

MARGIN = 1.2
"""Downward acceleration counted as impossible, in multiples of gravity. Mocap's second
differences are noisy (a person's own walk reaches 0.25 g, a run 1.4 g at single frames), so
a frame counts only past this."""


def com_heights(model: mujoco.MjModel, qpos: np.ndarray) -> np.ndarray:
    """Height ``(T,)`` of the centre of mass of the body that carries the model's first joint
    (the character; scene props are other subtrees) at each pose of ``qpos`` ``(T, k)``, whose
    ``k <= nq`` leading coordinates are the character's (the rest keep the model's defaults)."""
    qpos = np.asarray(qpos, dtype=np.float64)
    if qpos.ndim != 2 or qpos.shape[1] > model.nq:
        raise ValueError(f"qpos must be (frames, <= {model.nq}), got {qpos.shape}")
    root = int(model.jnt_bodyid[0]) if model.njnt else 0
    data = mujoco.MjData(model)
    out = np.empty(len(qpos))
    for t, q in enumerate(qpos):
        data.qpos[: q.shape[0]] = q
        mujoco.mj_kinematics(model, data)
        mujoco.mj_comPos(model, data)
        out[t] = data.subtree_com[root, 2]
    return out


def vertical_acceleration(heights: np.ndarray, fps: float) -> np.ndarray:
    """Second differences of ``heights`` ``(T,)`` sampled at ``fps``, averaged over three
    frames: ``(T - 4,)`` values, for frames 2 .. T-3 (exact for a parabola; empty when there
    are fewer than five frames)."""
    heights = np.asarray(heights, dtype=np.float64)
    if len(heights) < 5:
        return np.zeros(0)
    acc = (heights[2:] - 2.0 * heights[1:-1] + heights[:-2]) * fps**2
    return np.convolve(acc, np.ones(3) / 3.0, mode="valid")


def over_gravity_share(
    model: mujoco.MjModel, qpos: np.ndarray, fps: float, margin: float = MARGIN
) -> float:
    """Share of the frames of ``qpos`` at which the centre of mass falls faster than ``margin``
    times the model's gravity (0 for a clip under five frames: too short to tell)."""
    if len(qpos) < 5:
        return 0.0
    g = float(np.linalg.norm(model.opt.gravity))
    return float(np.mean(vertical_acceleration(com_heights(model, qpos), fps) < -margin * g))
