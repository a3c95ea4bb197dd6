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


def _z_extent(model: mujoco.MjModel, data: mujoco.MjData, ids: np.ndarray) -> tuple:
    """World ``(lowest z, highest z, centre)`` of the geoms ``ids`` from their local AABBs."""
    aabb = model.geom_aabb[ids]  # (k, 6): centre, half sizes in the geom frame
    rot = data.geom_xmat[ids].reshape(-1, 3, 3)
    centre = data.geom_xpos[ids] + np.einsum("kij,kj->ki", rot, aabb[:, :3])
    half_z = np.einsum("kj,kj->k", np.abs(rot[:, 2, :]), aabb[:, 3:])
    return centre[:, 2] - half_z, centre[:, 2] + half_z, centre


def foot_clearance(
    model: mujoco.MjModel, data: mujoco.MjData, feet: np.ndarray, props: np.ndarray
) -> np.ndarray:
    """``(n_props,)`` smallest clearance of a foot over each prop (``props``/``feet`` are
    ``(ngeom,)`` masks; props in index order); ``inf`` where no foot is over that prop."""
    prop_ids, foot_ids = np.nonzero(props)[0], np.nonzero(feet)[0]
    out = np.full(len(prop_ids), np.inf)
    if not len(prop_ids) or not len(foot_ids):
        return out
    foot_low, _, foot_centre = _z_extent(model, data, foot_ids)
    _, prop_top, _ = _z_extent(model, data, prop_ids)
    aabb = model.geom_aabb[prop_ids]
    rot = data.geom_xmat[prop_ids].reshape(-1, 3, 3)
    centre = data.geom_xpos[prop_ids] + np.einsum("kij,kj->ki", rot, aabb[:, :3])
    # foot centres in each prop's frame: (props, feet, 3)
    local = np.einsum("kji,kfj->kfi", rot, foot_centre[None] - centre[:, None])
    # the footprint: the prop's horizontal extent (its two axes that lie most in the floor)
    over = np.ones(local.shape[:2], dtype=bool)
    for axis in range(3):
        flat = np.abs(rot[:, 2, axis]) < 0.7  # this prop axis lies roughly horizontal
        inside = np.abs(local[..., axis]) <= aabb[:, None, 3 + axis]
        over &= np.where(flat[:, None], inside, True)
    clearance = foot_low[None, :] - prop_top[:, None]
    return np.where(over, clearance, np.inf).min(axis=1)
