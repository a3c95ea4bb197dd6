"""How high a foot passes over a scene prop: the evidence for "steps over the box".

Contacts (:mod:`retarget.eval.prop_hits`) say when a foot touches a box; they cannot tell a
foot lifted over a box from one that walked around it. This measures, for every prop geom,
the clearance of each foot geom whose centre is above the prop's footprint: the foot's lowest
point minus the prop's highest, from the geoms' bounding boxes in their current pose (so it
works for any geom type). Negative clearance is a foot sunk into or standing on the top.
"""

from __future__ import annotations

import mujoco
import numpy as np


def world_boxes(
    model: mujoco.MjModel, data: mujoco.MjData, ids: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The geoms ``ids`` as posed boxes from their local AABBs: world ``centre (k, 3)``,
    rotation ``(k, 3, 3)``, half sizes ``(k, 3)`` along the geom axes, lowest and highest z."""
    aabb = model.geom_aabb[ids]  # (k, 6): centre, half sizes in the geom frame
    rot = data.geom_xmat[ids].reshape(-1, 3, 3)
    centre = data.geom_xpos[ids] + np.einsum("kij,kj->ki", rot, aabb[:, :3])
    half = aabb[:, 3:]
    half_z = np.einsum("kj,kj->k", np.abs(rot[:, 2, :]), half)
    return centre, rot, half, centre[:, 2] - half_z, centre[:, 2] + half_z


def foot_clearance(
    model: mujoco.MjModel, data: mujoco.MjData, feet: np.ndarray, props: np.ndarray
) -> np.ndarray:
    """``(n_props,)`` smallest clearance of a foot over each prop (``props``/``feet`` are
    ``(ngeom,)`` masks; props in index order); ``inf`` where no foot is over that prop."""
    prop_ids, foot_ids = np.nonzero(props)[0], np.nonzero(feet)[0]
    if not len(prop_ids) or not len(foot_ids):
        return np.full(len(prop_ids), np.inf)
    foot_centre, _, _, foot_low, _ = world_boxes(model, data, foot_ids)
    centre, rot, half, _, prop_top = world_boxes(model, data, prop_ids)
    # foot centres in each prop's frame: (props, feet, 3)
    local = np.einsum("kji,kfj->kfi", rot, foot_centre[None] - centre[:, None])
    # the footprint: the prop's extent along its axes that lie roughly in the floor plane
    flat = np.abs(rot[:, 2, :]) < 0.7  # (props, 3)
    inside = np.abs(local) <= half[:, None, :]
    over = (inside | ~flat[:, None, :]).all(axis=-1)
    clearance = foot_low[None, :] - prop_top[:, None]
    return np.where(over, clearance, np.inf).min(axis=1)
