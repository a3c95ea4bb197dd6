"""Stance feet put on the floor: a root height correction of a kinematically retargeted clip.

Rough kinematic retargeting (:mod:`retarget.character.kinematic`) scales the root path by the
character's rest root height and copies the human's joint angles. On a body whose legs are
proportioned unlike a person's the feet then miss the floor: measured on held-out Bandai
Namco clips (``benchmarks/reference_ground.py``), the Dino's stance feet stand a median 3.3 cm
above it on walks and 7.3 cm on runs, whose reference is off the floor in 89% of frames, and a
180 kg body asked to stay there needs a root force of more than its weight in those frames,
which no policy and no planner has. Physics then holds the body
lower than its reference, and every tracker inherits a pose error the reference itself
makes.

:func:`ground_feet` lowers (or raises) the root in each frame where the performer has a
foot down (the clip's contact labels) so that foot's lowest point is on the floor, carries
the correction linearly across frames with no foot down (flight keeps its arc, shifted),
and smooths it over a short window so a change of stance foot is no jump in the root's
speed. Joint angles are untouched. Why by hand: the correction needs the character's own
geoms and the performer's contact labels together, which no retargeting library offers for
a MuJoCo model.
"""

from __future__ import annotations

from collections.abc import Sequence

import mujoco
import numpy as np

from retarget.character.kinematic import foot_geoms, geoms_lowest_point

SMOOTH_SECONDS = 0.2
"""Width of the moving average over the per-frame correction (seconds)."""


def lowest_points(model: mujoco.MjModel, qpos: np.ndarray, geoms: Sequence[int]) -> np.ndarray:
    """Lowest world height over ``geoms`` in each frame ``(T,)``, metres, from forward
    kinematics of ``qpos`` ``(T, nq)`` (the character's block; the rest of the model stays at
    its defaults)."""
    data = mujoco.MjData(model)
    ids = list(geoms)
    xpos = np.zeros((len(qpos), len(ids), 3))
    xmat = np.zeros((len(qpos), len(ids), 9))
    nq = qpos.shape[1]
    for t in range(len(qpos)):
        data.qpos[:nq] = qpos[t]
        mujoco.mj_kinematics(model, data)
        xpos[t], xmat[t] = data.geom_xpos[ids], data.geom_xmat[ids]
    return geoms_lowest_point(model, xpos, xmat, ids)


def stance_heights(
    model: mujoco.MjModel, qpos: np.ndarray, contacts: np.ndarray, feet: Sequence[Sequence[int]]
) -> np.ndarray:
    """Per frame ``(T,)``: the lowest point of the feet the performer has down (``contacts``
    ``(T, len(feet))``; ``feet``: body ids per foot), metres above the floor; NaN in frames
    with no foot down."""
    contacts = np.asarray(contacts, dtype=bool)
    if contacts.shape != (len(qpos), len(feet)):
        raise ValueError(
            f"contact labels of shape {contacts.shape} for {len(qpos)} frames and {len(feet)} feet"
        )
    lows = np.stack([lowest_points(model, qpos, g) for g in foot_geoms(model, feet)], axis=1)
    stance = np.where(contacts, lows, np.inf).min(axis=1)
    return np.where(np.isfinite(stance), stance, np.nan)


def ground_feet(
    model: mujoco.MjModel,
    qpos: np.ndarray,
    contacts: np.ndarray,
    feet: Sequence[Sequence[int]],
    fps: float,
) -> np.ndarray:
    """``qpos`` ``(T, nq)`` with its root height corrected so that the performer's stance
    feet stand on the floor (z = 0); ``contacts`` ``(T, 2)`` are the clip's left/right foot
    labels and ``feet`` the character's left/right foot body ids. A clip with no foot down in
    any frame comes back unchanged."""
    if len(qpos) == 0 or not np.asarray(contacts, dtype=bool).any():
        return qpos
    stance = stance_heights(model, qpos, contacts, feet)
    down = np.flatnonzero(np.isfinite(stance))
    frames = np.arange(len(qpos))
    shift = np.interp(frames, down, -stance[down])
    width = max(1, round(SMOOTH_SECONDS * fps) | 1)  # odd, so the window is centred
    if width > 1 and len(shift) > 1:
        pad = width // 2
        padded = np.pad(shift, pad, mode="edge")
        shift = np.convolve(padded, np.ones(width) / width, mode="valid")
    out = np.array(qpos, dtype=np.float64, copy=True)
    out[:, 2] += shift
    return out
