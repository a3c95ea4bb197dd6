"""Whether a body could follow a reference at all: its centre of mass may not fall faster
than gravity.

Contacts push and friction drags, but nothing pulls a body down harder than gravity does. A
reference whose centre of mass accelerates downward by more than ``g`` asks for a drop no
controller can give, and a tracker's error there says nothing about the tracker. Retargeting
to a larger body scales every length and keeps the person's timing, so every acceleration
grows with the scale: a person's run played by the 2.5 m Dino (1.43 times a 1.75 m person)
asks for 1.43 times the person's downward accelerations.

The measure is how far the reference's centre of mass drops *beyond* free fall, summed over
the stretches where it falls faster than ``g`` (the excess acceleration integrated twice over
each stretch, from the stretch's own start), per second of motion. It is a length a tracker
must lose, not a count of frames: a person's own runs on the human character (the character's
masses are not the person's, and mocap is noisy) show 25-72 mm per second and are tracked at
16-22 mm; the same runs on the Dino ask for 128-200 mm per second; walks and gestures, none.
"""

from __future__ import annotations

import mujoco
import numpy as np


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


def drop_beyond_fall(heights: np.ndarray, fps: float, gravity: float = 9.81) -> float:
    """Metres by which ``heights`` ``(T,)``, sampled at ``fps``, drop further than free fall
    would take them, summed over every stretch of frames whose downward acceleration (second
    differences) exceeds ``gravity``."""
    heights = np.asarray(heights, dtype=np.float64)
    if len(heights) < 3:
        return 0.0
    dt = 1.0 / fps
    excess = np.maximum(0.0, -(heights[2:] - 2.0 * heights[1:-1] + heights[:-2]) / dt**2 - gravity)
    total = speed = 0.0
    for e in excess:
        speed = speed + e * dt if e > 0 else 0.0  # a new stretch starts from rest
        total += speed * dt
    return total


def drop_beyond_fall_per_second(model: mujoco.MjModel, qpos: np.ndarray, fps: float) -> float:
    """:func:`drop_beyond_fall` of the character's centre of mass over the reference poses
    ``qpos`` ``(T, k)``, per second of motion (m/s; 0 for a single pose)."""
    if len(qpos) < 2:
        return 0.0
    g = float(np.linalg.norm(model.opt.gravity))
    seconds = (len(qpos) - 1) / fps
    return drop_beyond_fall(com_heights(model, qpos), fps, g) / seconds
