"""Joint torques that move the reference, so the planner's PD targets do not sag or lag.

A PD servo holding a limb against gravity sags by ``torque / kp``; a servo swinging it lags
by its inertia. Inverse dynamics of the reference (``mj_inverse`` on its poses, velocities
and accelerations, constraints off) gives the torque each joint needs, but it treats the
root as if it could push itself: a stance leg's load comes through the floor, which the
free-floating inverse does not know (adding the bias torques to every joint was measured to
make walks worse). So each frame's contacts are found on the reference pose itself (the
model's own collision, every geom's margin widened a little so a foot about to land counts).
Either a joint gets its inverse torque only in frames where no body below it touches
anything (arms, head, spine above the hips, a swing leg), or (``support``) the root's wrench
is handed to the contacts and every joint gets what is left. Why by hand: no library gives
contact-aware inverse dynamics of a MuJoCo model.
"""

from __future__ import annotations

import mujoco
import numpy as np


def subtree_masks(model: mujoco.MjModel, joint_ids: np.ndarray) -> np.ndarray:
    """``(len(joint_ids), nbody)`` bool: the bodies each joint moves (its body's subtree).
    MuJoCo numbers every body after its parent, so one pass in body order fills them."""
    parent = np.asarray(model.body_parentid)
    roots = np.asarray(model.jnt_bodyid[joint_ids], dtype=np.intp)
    mask = np.zeros((len(roots), model.nbody), dtype=bool)
    for b in range(1, model.nbody):
        mask[:, b] = mask[:, parent[b]] | (roots == b)
    return mask


def reference_torques(
    model: mujoco.MjModel,
    qpos: np.ndarray,
    qvel: np.ndarray,
    dt: float,
    joint_ids: np.ndarray,
    margin: float = 0.02,
    support: bool = False,
) -> np.ndarray:
    """``(T, len(joint_ids))``: the torque each joint needs to move through reference frames
    ``qpos``/``qvel`` (``(T, nq)``/``(T, nv)`` of the whole model) when none of its bodies
    touch anything in that frame, else 0. Accelerations are central differences of ``qvel``
    (one-sided at the ends).

    ``support``: the touching joints get torques too. The free root cannot push itself, so
    the wrench the inverse asks of it must come through the contacts with the world: it is
    shared out as the least-norm set of forces at the contact points that supplies it (one
    stance foot carries it all, two share it), and each joint's torque is its inverse torque
    less what those forces transmit through it."""
    T = len(qpos)
    if T == 0:
        return np.zeros((0, len(joint_ids)))
    qacc = np.gradient(qvel, dt, axis=0) if T > 1 else np.zeros_like(qvel)
    touch = model.__copy__()
    touch.geom_margin[:] = np.maximum(touch.geom_margin, margin)
    free = model.__copy__()
    free.opt.disableflags |= int(mujoco.mjtDisableBit.mjDSBL_CONSTRAINT)
    dt_data, df = mujoco.MjData(touch), mujoco.MjData(free)
    masks = subtree_masks(model, joint_ids)
    free_joint = np.flatnonzero(np.asarray(model.jnt_type) == mujoco.mjtJoint.mjJNT_FREE)
    own = (subtree_masks(model, free_joint[:1])[0] if free_joint.size
           else np.zeros(model.nbody, dtype=bool))  # fmt: skip
    root_dofs = (int(model.jnt_dofadr[free_joint[0]]) + np.arange(6) if free_joint.size
                 else np.arange(0))  # fmt: skip
    jacp = np.zeros((3, model.nv))
    dofs = np.asarray(model.jnt_dofadr[joint_ids], dtype=np.intp)
    geom_body = np.asarray(model.geom_bodyid)
    out = np.zeros((T, len(joint_ids)))
    for t in range(T):
        dt_data.qpos[:] = qpos[t]
        mujoco.mj_kinematics(touch, dt_data)
        mujoco.mj_collision(touch, dt_data)
        touched = np.zeros(model.nbody, dtype=bool)
        n = dt_data.ncon
        near = np.zeros((0, 2), dtype=np.intp)
        points = np.zeros((0, 3))
        if n:
            geoms = np.asarray(dt_data.contact.geom[:n])
            close = np.asarray(dt_data.contact.dist[:n]) < margin
            near, points = geoms[close], np.asarray(dt_data.contact.pos[:n])[close]
            touched[geom_body[near.ravel()]] = True
        touched[0] = False  # the world body is not under any joint
        df.qpos[:], df.qvel[:], df.qacc[:] = qpos[t], qvel[t], qacc[t]
        mujoco.mj_inverse(free, df)
        qfrc = df.qfrc_inverse.copy()
        if not support:
            out[t] = np.where((masks & touched[None]).any(-1), 0.0, qfrc[dofs])
            continue
        bodies = geom_body[near]
        world = own[bodies[:, 0]] != own[bodies[:, 1]]  # character against the world
        if world.any() and root_dofs.size:
            jac = []
            for pair, point in zip(bodies[world], points[world], strict=True):
                body = int(pair[0] if own[pair[0]] else pair[1])
                mujoco.mj_jac(free, df, jacp, None, point, body)
                jac.append(jacp.copy())
            J = np.concatenate(jac)  # (3k, nv): forces at the points in world axes
            force = np.linalg.lstsq(J[:, root_dofs].T, qfrc[root_dofs], rcond=None)[0]
            qfrc = qfrc - J.T @ force
        out[t] = qfrc[dofs]
    return out
