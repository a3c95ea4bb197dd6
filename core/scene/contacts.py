"""Reference scene contact labels: which body groups of the kinematic reference touch the scene.

QuestEnvSim (Sec. 3.3.2) labels contacts "by using the simulator's collision detection
algorithm on the mocap reference motions". Here every library frame's retargeted pose is put
into the environment's own compiled world (character, scene props, floor) and MuJoCo's
collision detection (``mj_collision``) runs with a ``margin`` on the character's geoms: a geom
within ``margin`` of a geom that is not the character's counts as touching it, since kinematic
retargeting leaves feet and seats a few millimetres to centimetres apart or overlapping. A body
group is in contact when any of its bodies is. This runs once, when the reference is built,
never per step.

Randomization: the labels are computed against the scene at its default (un-randomized)
placement, the mocap bodies' poses in the model. Per-episode placement noise is at most 8 cm
and 0.1 rad (Sec. 3.4), small enough that a contact of the reference stays the contact the
policy should make; the paper keeps its labels fixed under randomization too.
"""

from __future__ import annotations

import copy
from typing import TYPE_CHECKING

from retarget.kinds.state import Layout

if TYPE_CHECKING:
    import mujoco
    import numpy as np

DEFAULT_MARGIN = 0.03
"""Metres within which a reference geom counts as touching the scene."""

CONTACT_LINKS = ("left_foot", "right_foot", "left_hand", "right_hand", "pelvis", "spine")
"""The body groups of QuestEnvSim's contact state (Sec. 3.3.2: feet, hands, pelvis, spine)."""

CONTACT_NEWTONS = 50.0
"""Upward contact force above which a simulated link counts as in contact (Sec. 3.3.2)."""


def group_matrix(model: mujoco.MjModel, layout: Layout) -> np.ndarray:
    """``(nbody, G)`` bool: model body ``b`` belongs to group ``g`` (``layout.body_groups``
    order); rows of bodies that are not the character's are all false."""
    import numpy as np
    groups = list(layout.body_groups.values())
    member = np.zeros((model.nbody, len(groups)), dtype=bool)
    for g, idx in enumerate(groups):
        for i in idx:
            member[layout.body_ids[i], g] = True
    return member


def scene_contact_labels(
    model: mujoco.MjModel,
    layout: Layout,
    qpos: np.ndarray,
    margin: float = DEFAULT_MARGIN,
    mocap: tuple[np.ndarray, np.ndarray] | None = None,
) -> np.ndarray:
    """``(T, G)`` bool labels of full-model poses ``qpos`` ``(T, model.nq)``, one column per
    body group of ``layout`` (see the module doc); ``mocap``: every mocap body's position and
    quaternion for these poses (default: the compiled placement)."""
    import mujoco
    import numpy as np
    m = copy.deepcopy(model)  # margins only for labelling, not in the simulated model
    character = np.zeros(m.nbody, dtype=bool)
    character[list(layout.body_ids)] = True
    mine = character[m.geom_bodyid]
    m.geom_margin[mine] = np.maximum(m.geom_margin[mine], margin)
    m.geom_gap[mine] = 0.0
    member = group_matrix(m, layout)
    data = mujoco.MjData(m)
    if mocap is not None:
        data.mocap_pos[:], data.mocap_quat[:] = mocap
    out = np.zeros((len(qpos), member.shape[1]), dtype=bool)
    for f in range(len(qpos)):  # preprocessing, once per library frame
        data.qpos[:] = qpos[f]
        mujoco.mj_kinematics(m, data)
        mujoco.mj_collision(m, data)
        if data.ncon == 0:
            continue
        con = data.contact
        geoms = np.asarray(con.geom[: data.ncon]).reshape(-1, 2)
        close = np.asarray(con.dist[: data.ncon]) < margin
        bodies = m.geom_bodyid[geoms]  # (ncon, 2)
        ours = character[bodies]
        scene = ours ^ ours[:, ::-1]  # exactly one side is the character's
        hit = close[:, None] & scene & ours
        out[f] = member[bodies[hit]].any(axis=0)
    return out
