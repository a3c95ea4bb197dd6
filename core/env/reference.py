"""The kinematic reference of one character over a motion library, precomputed once.

Every library frame gets the kinematically retargeted character pose (``qpos``), its
velocities (finite differences at the control rate), the world poses of the bodies and role
sites (MuJoCo forward kinematics) and its scene contact labels per body group
(:mod:`retarget.scene.contacts`) and the torque each actuated joint needs to move along it
(:mod:`retarget.sim.inverse_dynamics`, a residual policy's feedforward). At run time a
step's reference is pure indexing into these flat arrays with the library's ``(N,)`` row
indices: no kinematics and no loops per step.
"""

from __future__ import annotations

import itertools
from collections.abc import Sequence

import mujoco
import numpy as np
import torch

from retarget.character.grounding import ground_feet
from retarget.character.kinematic import retarget_clip
from retarget.env.reference_cache import load_reference, reference_key, store_reference
from retarget.errors import PluginError
from retarget.kinds import Character
from retarget.kinds.state import Layout, SimState
from retarget.motion.clip import MotionClip
from retarget.motion.hinge_elbows import hinge_elbows
from retarget.scene.contacts import DEFAULT_MARGIN, scene_contact_labels
from retarget.sim.batched import body_velocities
from retarget.sim.inverse_dynamics import reference_torques


def _velocities(model: mujoco.MjModel, qpos: np.ndarray, fps: float) -> np.ndarray:
    """``qvel`` of a pose sequence by central differences (one-sided at the ends)."""
    t = len(qpos)
    qvel = np.zeros((t, model.nv))
    if t < 2:
        return qvel
    for i in range(t):  # preprocessing, once per frame of the library
        a, b = max(i - 1, 0), min(i + 1, t - 1)
        mujoco.mj_differentiatePos(model, qvel[i], (b - a) / fps, qpos[a], qpos[b])
    return qvel


class CharacterReference:
    """Flat per-frame reference arrays of ``character`` for ``clips`` (in library order)."""

    def __init__(
        self,
        character: Character,
        model: mujoco.MjModel,
        layout: Layout,
        clips: Sequence[MotionClip],
        contact_margin: float = DEFAULT_MARGIN,
        mocap: Sequence[tuple[np.ndarray, np.ndarray] | None] | None = None,
        ground: bool = False,
        hinge: bool = False,
    ) -> None:
        """``mocap``: per clip, every mocap body's position and quaternion while its scene
        contacts are labelled (None: the compiled placement). ``ground``: the root height
        corrected so the performer's stance feet stand on the floor
        (:func:`retarget.character.grounding.ground_feet`). ``hinge``: the clips' elbows
        rewritten as hinges first (:mod:`retarget.motion.hinge_elbows`)."""
        joint_map = character.joint_map()
        if joint_map is None:
            raise PluginError(
                "has no joint map, so human motion cannot be retargeted onto it",
                plugin=f"character {character.name}",
            )
        if hinge:
            clips = [hinge_elbows(c) for c in clips]
        key = reference_key(model, joint_map, clips, contact_margin, mocap, ground)
        cached = load_reference(key)
        if cached is None:
            feet = foot_bodies(layout, character.name) if ground else None
            cached = _compute(model, layout, joint_map, clips, contact_margin, mocap, feet)
            store_reference(key, cached)
        qpos, qvel, labels = cached.pop("qpos"), cached.pop("qvel"), cached.pop("labels")
        self._torque = cached.pop("joint_torque")
        self._actuator_dofs = _actuator_dofs(model)
        arrays = cached
        self.scene_contacts = torch.as_tensor(labels, dtype=torch.bool)
        # the character's block only: joints of articulated scene props follow it and keep
        # their defaults at resets
        qpos, qvel = qpos[:, : layout.nq], qvel[:, : layout.nv]
        f32 = torch.float32
        self.qpos = torch.as_tensor(qpos, dtype=f32)
        self.qvel = torch.as_tensor(qvel, dtype=f32)
        self.qpos64 = qpos  # exact poses for resets (RSI)
        self.qvel64 = qvel
        self.arrays = {k: torch.as_tensor(v, dtype=f32) for k, v in arrays.items()}

    @property
    def num_frames(self) -> int:
        return int(self.qpos.shape[0])

    def use_servos(self, model: mujoco.MjModel) -> None:
        """Express the reference's joint torques as PD-target offsets of ``model``'s servos
        (``SimState.pd_feedforward``): ``(torque + kd * qdot) / kp`` per actuator, 0 where an
        actuator is no PD servo, and no more than the offset at which the servo reaches its
        force limit (a larger one asks for torque it cannot give: a kick's peak
        acceleration would otherwise ask for 10 rad). Called once the simulator has set the
        actuation up."""
        kp = -np.asarray(model.actuator_biasprm[:, 1], dtype=np.float64)
        kd = -np.asarray(model.actuator_biasprm[:, 2], dtype=np.float64)
        dofs = self._actuator_dofs
        servo = (kp > 0) & (dofs >= 0)
        gain = np.where(servo, kp, 1.0)
        qd = np.where(dofs >= 0, self.qvel64[:, np.maximum(dofs, 0)], 0.0)
        limited = np.asarray(model.actuator_forcelimited, dtype=bool)
        reach = np.where(limited, np.asarray(model.actuator_forcerange[:, 1]) / gain, np.inf)
        offset = np.clip((self._torque + kd * qd) / gain, -reach, reach)
        offset = np.where(servo, offset, 0.0)
        self.arrays["pd_feedforward"] = torch.as_tensor(offset, dtype=torch.float32)

    def pose(self, rows: torch.Tensor) -> SimState:
        """The reference state at flat library rows ``(N,)`` (contact forces are zero)."""
        a = self.arrays
        return SimState(
            qpos=self.qpos[rows],
            qvel=self.qvel[rows],
            body_pos=a["body_pos"][rows],
            body_quat=a["body_quat"][rows],
            body_linvel=a["body_linvel"][rows],
            body_angvel=a["body_angvel"][rows],
            site_pos=a["site_pos"][rows],
            site_quat=a["site_quat"][rows],
            contact_force=torch.zeros(rows.shape[0], a["body_pos"].shape[1]),
            contact_force_up=torch.zeros(rows.shape[0], a["body_pos"].shape[1]),
            pd_feedforward=a["pd_feedforward"][rows] if "pd_feedforward" in a else None,
        )


def foot_bodies(layout: Layout, character: str) -> list[list[int]]:
    """Model body ids of the left and right foot (the ``left_foot``/``right_foot`` groups)."""
    groups = layout.body_groups
    missing = [g for g in ("left_foot", "right_foot") if g not in groups]
    if missing:
        raise PluginError(
            f"has no body group {' or '.join(missing)}, so its stance feet cannot be put on "
            "the floor (env.ground_feet)",
            plugin=f"character {character}",
        )
    ids = np.asarray(layout.body_ids)
    return [ids[list(groups[g])].tolist() for g in ("left_foot", "right_foot")]


def _actuator_dofs(model: mujoco.MjModel) -> np.ndarray:
    """``(nu,)``: the degree of freedom each actuator drives when it drives one hinge or
    slide joint, else -1."""
    joints = np.asarray(model.actuator_trnid[:, 0], dtype=np.intp)
    on_joint = np.asarray(model.actuator_trntype) == int(mujoco.mjtTrn.mjTRN_JOINT)
    kind = np.asarray(model.jnt_type)[np.where(on_joint, joints, 0)]
    one_dof = np.isin(kind, [int(mujoco.mjtJoint.mjJNT_HINGE), int(mujoco.mjtJoint.mjJNT_SLIDE)])
    return np.where(on_joint & one_dof, np.asarray(model.jnt_dofadr)[joints], -1).astype(np.intp)


def _compute(
    model: mujoco.MjModel,
    layout: Layout,
    joint_map,
    clips: Sequence[MotionClip],
    contact_margin: float,
    mocap: Sequence[tuple[np.ndarray, np.ndarray] | None] | None,
    feet: list[list[int]] | None = None,
) -> dict[str, np.ndarray]:
    """Retargeting (its stance ``feet`` put on the floor when given), velocities, joint
    torques, forward kinematics and contact labels of every frame."""
    qpos_parts, qvel_parts, torque_parts = [], [], []
    dofs = _actuator_dofs(model)
    joints = np.asarray(model.actuator_trnid[:, 0], dtype=np.intp)[dofs >= 0]
    for clip in clips:
        qpos_clip = retarget_clip(clip, model, joint_map).qpos
        if feet is not None:
            qpos_clip = ground_feet(model, qpos_clip, clip.contacts, feet, clip.fps)
        qpos_parts.append(qpos_clip)
        qvel_parts.append(_velocities(model, qpos_clip, clip.fps))
        torque = np.zeros((len(qpos_clip), model.nu))
        # the load of a stance foot comes through the floor (the scene at its compiled
        # placement): shared out over the reference pose's contacts
        torque[:, dofs >= 0] = reference_torques(model, qpos_clip, qvel_parts[-1],
                                                 1.0 / clip.fps, joints, support=True)  # fmt: skip
        torque_parts.append(torque)
    qpos = np.concatenate(qpos_parts)
    qvel = np.concatenate(qvel_parts)
    frames = len(qpos)
    bodies = np.asarray(layout.body_ids)
    sites = np.asarray(layout.site_ids)
    arrays = {
        "body_pos": np.zeros((frames, len(bodies), 3)),
        "body_quat": np.zeros((frames, len(bodies), 4)),
        "body_linvel": np.zeros((frames, len(bodies), 3)),
        "body_angvel": np.zeros((frames, len(bodies), 3)),
        "site_pos": np.zeros((frames, len(sites), 3)),
        "site_quat": np.zeros((frames, len(sites), 4)),
    }
    data = mujoco.MjData(model)
    roots = model.body_rootid[bodies]
    cvel = np.zeros((frames, len(bodies), 6))
    com = np.zeros((frames, len(bodies), 3))
    for f in range(frames):  # preprocessing: forward kinematics of every library frame
        data.qpos[:] = qpos[f]
        data.qvel[:] = qvel[f]
        mujoco.mj_kinematics(model, data)
        mujoco.mj_comPos(model, data)
        mujoco.mj_comVel(model, data)
        arrays["body_pos"][f] = data.xpos[bodies]
        arrays["body_quat"][f] = data.xquat[bodies]
        cvel[f] = data.cvel[bodies]
        com[f] = data.subtree_com[roots]
        arrays["site_pos"][f] = data.site_xpos[sites]
        for k, s in enumerate(sites):
            mujoco.mju_mat2Quat(arrays["site_quat"][f, k], data.site_xmat[s])
    # which body groups touch the (un-randomized) scene, per frame: the contact reward's
    # and the evaluation's labels
    if mocap is None or all(m is None for m in mocap):
        labels = scene_contact_labels(model, layout, qpos, contact_margin)
    else:
        bounds = np.cumsum([0] + [len(p) for p in qpos_parts])
        labels = np.concatenate([
            scene_contact_labels(model, layout, qpos[a:b], contact_margin, mocap[c])
            for c, (a, b) in enumerate(itertools.pairwise(bounds))
        ])  # fmt: skip
    ang, lin = body_velocities(cvel, arrays["body_pos"], com)
    arrays["body_angvel"], arrays["body_linvel"] = ang, lin
    return {"qpos": qpos, "qvel": qvel, "labels": labels,
            "joint_torque": np.concatenate(torque_parts), **arrays}  # fmt: skip
