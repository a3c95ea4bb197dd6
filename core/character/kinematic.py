"""Batched kinematic retargeting of a human clip onto a character, and its foot artefacts.

This is the paper's "rough kinematic retargeting" (Sec. 3.4, Fig. 4): the root trajectory is
scaled by the size ratio, mapped joints copy the human's joint angles (through the character's
:class:`~retarget.character.joint_map.JointMap`), and unmapped joints (tails, ears) stay at their
default. The result is the reference the simulated character imitates; its foot sliding, penetration
and floating are the artefacts physics removes, measured here as a baseline.

Everything is computed for a whole clip at once: rotations and Euler decompositions are numpy
over all frames; only forward kinematics for the artefact measurement loops over frames (it is
MuJoCo's own ``mj_kinematics``, a few microseconds per frame).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from retarget.character.joint_map import JointMap
from retarget.errors import RecipeError
from retarget.geometry import rotations as rot
from retarget.motion import skeleton as sk
from retarget.motion.clip import MotionClip

if TYPE_CHECKING:
    import mujoco

CLIP_MARGIN = 1e-6
"""Retargeted angles are clipped this far (radians) inside the joint limits."""


@dataclass(frozen=True)
class HingeGroup:
    """A character joint as the model has it: its hinges (rotation order) and their axes."""

    name: str
    hinges: tuple[str, ...]
    axes: tuple[str, ...]
    qpos_adr: tuple[int, ...]


def hinge_groups(model: mujoco.MjModel) -> dict[str, HingeGroup]:
    """Character joints of a model built with :mod:`retarget.character.builder` conventions.

    Hinges of one body form a joint; a lone hinge keeps its name, a group of ``<j>_x``-style
    hinges is named ``<j>``. Works on any model following the convention, not only built-ins.
    """
    import mujoco
    by_body: dict[int, list[int]] = {}
    for j in range(model.njnt):
        if model.jnt_type[j] == mujoco.mjtJoint.mjJNT_HINGE:
            by_body.setdefault(int(model.jnt_bodyid[j]), []).append(j)
    groups: dict[str, HingeGroup] = {}
    for ids in by_body.values():
        names = [mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_JOINT, j) for j in ids]
        axes = []
        for j in ids:
            a = np.abs(model.jnt_axis[j])
            axes.append("xyz"[int(np.argmax(a))])
        if len(ids) == 1:
            gname = names[0]
        else:
            stems = {n.rsplit("_", 1)[0] for n in names}
            gname = stems.pop() if len(stems) == 1 else names[0]
        groups[gname] = HingeGroup(
            gname, tuple(names), tuple(axes), tuple(int(model.jnt_qposadr[j]) for j in ids)
        )
    return groups


def root_height_ratio(model: mujoco.MjModel, clip: MotionClip) -> float:
    """Character root height at rest over the subject's standing pelvis height.

    Scaling the whole root trajectory by it keeps a standing human's character standing (root
    at its rest height) and shortens or lengthens strides in proportion to the legs.
    """
    return float(model.qpos0[2]) / sk.standing_pelvis_height(clip.offsets)


def scaled_clip(clip: MotionClip, scale: float) -> MotionClip:
    """The clip as a person ``scale`` times the size would perform it about the world origin
    (root path and bones scaled): where the character's reference goes, so props placed from
    it (or given in the clip's frame and scaled by ``meta["scale"]``, the product of every
    scaling so far) fit the character."""
    total = float(clip.meta.get("scale", 1.0)) * scale  # type: ignore[arg-type]
    return clip.with_(root_pos=clip.root_pos * scale, offsets=clip.offsets * scale,
                      meta={**clip.meta, "scale": total})  # fmt: skip


@dataclass
class KinematicMotion:
    """A retargeted clip: character ``qpos (T, nq)`` at the clip's rate, and what was clipped."""

    qpos: np.ndarray
    fps: float
    root_scale: float
    clipped: dict[str, float]  # hinge -> fraction of frames clipped to its limits

    @property
    def clip_rate(self) -> float:
        """Fraction of (frame, mapped hinge) entries that hit a joint limit."""
        return float(np.mean(list(self.clipped.values()))) if self.clipped else 0.0


def retarget_clip(
    clip: MotionClip, model: mujoco.MjModel, joint_map: JointMap, *, root_scale: float | None = None
) -> KinematicMotion:
    """Kinematically retarget ``clip`` onto the character ``model`` (all frames at once)."""
    import mujoco
    groups = hinge_groups(model)
    joint_map.validate_against(sk.JOINT_NAMES, {g.name: g.axes for g in groups.values()})
    t = clip.num_frames
    qpos = np.tile(model.qpos0, (t, 1))
    scale = root_height_ratio(model, clip) if root_scale is None else root_scale
    qpos[:, 0:3] = clip.root_pos * scale
    qpos[:, 3:7] = rot.normalize(clip.local_rot[:, sk.ROOT])
    clipped: dict[str, float] = {}
    for cname, link in joint_map.links.items():
        group = groups[cname]
        q = rot.identity((t,))
        for h in link.human:  # parent first: q = q_parent * q_child
            q = rot.mul(q, clip.local_rot[:, sk.joint_index(h)])
        angles = joint_map.hinge_angles(cname, group.axes, q)
        for k, (hname, adr) in enumerate(zip(group.hinges, group.qpos_adr, strict=True)):
            jid = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_JOINT, hname)
            lo, hi = model.jnt_range[jid] + (CLIP_MARGIN, -CLIP_MARGIN)
            a = angles[:, k]
            clipped[hname] = float(np.mean((a < lo) | (a > hi)))
            qpos[:, adr] = np.clip(a, lo, hi)
    if not np.all(np.isfinite(qpos)):
        raise RecipeError(
            f"kinematic retargeting of clip '{clip.name}' produced non-finite joint angles"
        )
    return KinematicMotion(qpos=qpos, fps=clip.fps, root_scale=scale, clipped=clipped)


# ---------------------------------------------------------------------------------------------
# Foot artefacts of a kinematic motion
# ---------------------------------------------------------------------------------------------


def foot_geoms(model: mujoco.MjModel, feet: Sequence[Sequence[int]]) -> list[list[int]]:
    """The geoms of each foot's bodies (``feet``: body ids per foot)."""
    body = np.asarray(model.geom_bodyid)
    return [[g for g in range(model.ngeom) if int(body[g]) in set(ids)] for ids in feet]


def _body_ids(model: mujoco.MjModel, names: Sequence[str]) -> list[int]:
    import mujoco
    return [mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, n) for n in names]


def geoms_lowest_point(
    model: mujoco.MjModel, xpos: np.ndarray, xmat: np.ndarray, geoms: Sequence[int]
) -> np.ndarray:
    """Lowest world z over ``geoms`` per frame, from per-frame geom poses ``(T, G, ...)``."""
    import mujoco
    size = model.geom_size[list(geoms)]  # (G, 3)
    types = model.geom_type[list(geoms)]
    zrow = xmat[:, :, 6:9]  # third row of each geom's rotation: world z of its local axes
    half = np.empty(zrow.shape[:2])
    for g, (typ, sz) in enumerate(zip(types, size, strict=True)):
        row = zrow[:, g]
        if typ == mujoco.mjtGeom.mjGEOM_SPHERE:
            half[:, g] = sz[0]
        elif typ == mujoco.mjtGeom.mjGEOM_CAPSULE:
            half[:, g] = np.abs(row[:, 2]) * sz[1] + sz[0]
        elif typ == mujoco.mjtGeom.mjGEOM_ELLIPSOID:
            half[:, g] = np.sqrt(np.sum((row * sz) ** 2, axis=-1))
        else:  # box (and anything else, conservatively as a box)
            half[:, g] = np.sum(np.abs(row) * sz, axis=-1)
    return np.min(xpos[:, :, 2] - half, axis=1)


@dataclass(frozen=True)
class FootArtefacts:
    """Means over a clip, per character (metres, m/s).

    ``penetration``: depth of the lowest foot point below the floor, over all frames and feet;
    ``float``: height of the lowest foot point while the human's foot is in contact;
    ``sliding``: horizontal speed of the foot while the human's foot stays in contact.
    """

    penetration: float
    float: float
    sliding: float
    contact_frames: int


def foot_artefacts(
    model: mujoco.MjModel,
    motion: KinematicMotion,
    contacts: np.ndarray,
    feet: Mapping[str, Sequence[str]],
) -> FootArtefacts:
    """Measure the foot artefacts of ``motion`` against human contact labels ``(T, 2)``.

    ``feet`` maps ``left_foot``/``right_foot`` to body names (a character's body groups).
    """
    import mujoco
    data = mujoco.MjData(model)
    sides = [_body_ids(model, feet["left_foot"]), _body_ids(model, feet["right_foot"])]
    geoms = foot_geoms(model, sides)
    all_geoms = geoms[0] + geoms[1]
    t = motion.qpos.shape[0]
    xpos = np.empty((t, len(all_geoms), 3))
    xmat = np.empty((t, len(all_geoms), 9))
    foot_xy = np.empty((t, 2, 2))
    for i in range(t):
        data.qpos[:] = motion.qpos[i]
        mujoco.mj_kinematics(model, data)
        xpos[i] = data.geom_xpos[all_geoms]
        xmat[i] = data.geom_xmat[all_geoms]
        foot_xy[i, 0] = data.xpos[sides[0][0], :2]
        foot_xy[i, 1] = data.xpos[sides[1][0], :2]
    n0 = len(geoms[0])
    low = np.stack(
        [
            geoms_lowest_point(model, xpos[:, :n0], xmat[:, :n0], geoms[0]),
            geoms_lowest_point(model, xpos[:, n0:], xmat[:, n0:], geoms[1]),
        ],
        axis=1,
    )
    contacts = np.asarray(contacts, dtype=bool)
    penetration = float(np.mean(np.maximum(-low, 0.0)))
    floating = float(np.mean(np.maximum(low[contacts], 0.0))) if contacts.any() else 0.0
    speed = np.linalg.norm(np.diff(foot_xy, axis=0), axis=-1) * motion.fps  # (T-1, 2)
    held = contacts[1:] & contacts[:-1]
    sliding = float(np.mean(speed[held])) if held.any() else 0.0
    return FootArtefacts(
        penetration=penetration, float=floating, sliding=sliding, contact_frames=int(contacts.sum())
    )
