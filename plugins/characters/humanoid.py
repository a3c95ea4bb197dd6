"""A humanoid body on the canonical skeleton's proportions (used by ``human`` and ``jesse``).

Joint centres are the canonical T-pose joint positions (``retarget.motion.skeleton``) scaled to
the requested height, so a human clip maps onto it with identity rotations; only collars are
folded into the shoulders and ``spine``/``spine1`` into one abdomen joint.

Hinge orders put the axis along the bone in the middle (hips ``yzx``, shoulders ``xyz``), so
the Euler decomposition only degenerates at a 90 degree twist, which the limits exclude.
Limits (degrees) are generous anatomical ranges; signs follow the canonical frame (X forward,
Y left, Z up): a positive ``y`` bends a vertical bone forward, a positive knee bends backward.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

from retarget.character.builder import BodyBuilder, Box, Capsule, Joint, Sphere, ball, hinge, joint
from retarget.character.joint_map import JointLink, JointMap, elbow_link

from .common import scaled

# Table 4 of the paper (torque scale per joint family; unlisted families are not scaled). The
# paper's skeletons do not name wrists or toes; we scale them down (0.05 / 0.2) because a
# 300 N m wrist on a 0.4 kg hand only makes the hand shake.
JESSE_TORQUE_SCALES: Mapping[str, float] = {
    "spine": 0.25, "chest": 0.25, "neck": 0.1, "shoulder": 0.2, "elbow": 0.1, "wrist": 0.05,
    "hip": 1.0, "knee": 1.0, "ankle": 1.0, "toe": 0.2,
}


@dataclass(frozen=True)
class HumanoidShape:
    """Proportions that distinguish a realistic human from a cartoon one (radii in m at 1.75)."""

    pelvis_r: float = 0.09
    abdomen_r: float = 0.085
    chest_r: float = 0.105
    neck_r: float = 0.045
    head_r: float = 0.095
    upper_arm_r: float = 0.045
    forearm_r: float = 0.037
    hand_half: tuple[float, float, float] = (0.045, 0.075, 0.02)
    thigh_r: float = 0.068
    shin_r: float = 0.05
    foot_half_width: float = 0.045
    toes: bool = True  # a separate toe body (18 links) or a longer foot (16 links)
    chest_twist: bool = True  # chest is 3-DoF, else 2-DoF (Jesse's 32 DoF)
    rgba: tuple[float, float, float, float] = (0.72, 0.6, 0.5, 1.0)


def build_humanoid(name: str, height: float, torque: float, shape: HumanoidShape,
                   scales: Mapping[str, float] = JESSE_TORQUE_SCALES) -> BodyBuilder:
    """Bodies, joints and role sites of a humanoid ``height`` metres tall (crown to floor)."""
    import numpy as np

    from retarget.motion import skeleton as sk
    s = height / sk.REFERENCE_HEIGHT
    off = {n: tuple(o) for n, o in zip(sk.JOINT_NAMES, sk.rest_offsets(height), strict=True)}
    pelvis_z = sk.standing_pelvis_height(sk.rest_offsets(height))

    def t(fam: str) -> float:
        return torque * scales.get(fam, 1.0)

    def v(x: float, y: float, z: float) -> tuple[float, float, float]:
        return scaled((x, y, z), s)

    b = BodyBuilder(name, rgba=shape.rgba)
    b.root("pelvis", (0.0, 0.0, pelvis_z),
           [Capsule(v(0, -0.07, -0.01), v(0, 0.07, -0.01), shape.pelvis_r * s)])
    b.body("abdomen", "pelvis", off["spine"],
           [Capsule(v(0, -0.055, 0.04), v(0, 0.055, 0.04), shape.abdomen_r * s),
            Capsule(v(0, -0.06, 0.17), v(0, 0.06, 0.17), shape.abdomen_r * s)],
           ball("spine", (-35, 35), (-30, 70), (-45, 45), t("spine"), order="yzx"))
    chest_pos = np.add(off["spine1"], off["spine2"])
    chest_joint: Joint = (ball("chest", (-30, 30), (-30, 45), (-40, 40), t("chest"), order="yzx")
                          if shape.chest_twist else
                          joint("chest", {"y": (-30, 45), "x": (-30, 30)}, t("chest")))
    b.body("chest", "abdomen", tuple(chest_pos),
           [Capsule(v(0, -0.065, 0.03), v(0, 0.065, 0.03), shape.chest_r * s),
            Capsule(v(0, -0.08, 0.13), v(0, 0.08, 0.13), shape.chest_r * s)], chest_joint)
    # The crown sits exactly at ``height`` (the skeleton's joint chain fixes the head joint).
    neck_z = pelvis_z + off["spine"][2] + off["spine1"][2] + off["spine2"][2] + off["neck"][2]
    head_z = height - neck_z - shape.head_r * s
    b.body("head", "chest", off["neck"],
           [Capsule(v(0, 0, 0), v(0, 0, 0.09), shape.neck_r * s),
            Sphere((0.01 * s, 0.0, head_z), shape.head_r * s)],
           ball("neck", (-45, 45), (-50, 60), (-80, 80), t("neck"), order="yzx"))
    # Headset: at the eyes, in front of the head joint (the HMD is strapped to the face).
    b.site("head", "head", (0.09 * s, 0.0, off["head"][2] + 0.03 * s))

    for side, sgn, pre in (("left", 1.0, "l"), ("right", -1.0, "r")):
        shoulder = np.add(off[f"{side}_collar"], off[f"{side}_shoulder"])
        b.body(f"{pre}_upper_arm", "chest", tuple(shoulder),
               [Capsule(v(0, sgn * 0.02, 0), v(0, sgn * 0.26, 0), shape.upper_arm_r * s)],
               ball(f"{pre}_shoulder", (-120, 170) if sgn > 0 else (-170, 120), (-100, 100),
                    (-160, 80) if sgn > 0 else (-80, 160), t("shoulder"), order="xyz"))
        b.body(f"{pre}_forearm", f"{pre}_upper_arm", off[f"{side}_elbow"],
               [Capsule(v(0, sgn * 0.02, 0), v(0, sgn * 0.23, 0), shape.forearm_r * s)],
               hinge(f"{pre}_elbow", "z", *((-160, 5) if sgn > 0 else (-5, 160)), t("elbow")))
        hx, hy, hz = shape.hand_half
        b.body(f"{pre}_hand", f"{pre}_forearm", off[f"{side}_wrist"],
               [Box(v(0, sgn * (hy + 0.005), 0), v(hx, hy, hz))],
               joint(f"{pre}_wrist", {"x": (-80, 80), "z": (-45, 45)}, t("wrist")))
        # Controller: held in the palm, just below the hand's centre.
        b.site(f"{side}_hand", f"{pre}_hand", v(0, sgn * 0.07, -0.03))

        b.body(f"{pre}_thigh", "pelvis", off[f"{side}_hip"],
               [Capsule(v(0, 0, -0.03), v(0, 0, -0.38), shape.thigh_r * s)],
               ball(f"{pre}_hip", (-40, 80) if sgn > 0 else (-80, 40), (-140, 40), (-60, 60),
                    t("hip"), order="yzx"))
        b.body(f"{pre}_shin", f"{pre}_thigh", off[f"{side}_knee"],
               [Capsule(v(0, 0, -0.03), v(0, 0, -0.36), shape.shin_r * s)],
               hinge(f"{pre}_knee", "y", -5, 160, t("knee")))
        ankle_h = sk.ANKLE_HEIGHT_175 * s
        toe = off[f"{side}_toe"]
        w = shape.foot_half_width * s
        if shape.toes:
            foot = [Box(((toe[0] - 0.06 * s) / 2, 0.0, -ankle_h / 2 - 0.01 * s),
                        ((toe[0] + 0.06 * s) / 2, w, ankle_h / 2 - 0.01 * s))]
        else:
            tip = toe[0] + 0.07 * s
            foot = [Box(((tip - 0.06 * s) / 2, 0.0, -ankle_h / 2 - 0.01 * s),
                        ((tip + 0.06 * s) / 2, w, ankle_h / 2 - 0.01 * s))]
        b.body(f"{pre}_foot", f"{pre}_shin", off[f"{side}_ankle"], foot,
               joint(f"{pre}_ankle", {"y": (-50, 50), "x": (-35, 35)}, t("ankle")))
        if shape.toes:
            toe_h = ankle_h + toe[2]  # toe joint height above the floor
            b.body(f"{pre}_toes", f"{pre}_foot", toe,
                   [Box((0.035 * s, 0.0, -toe_h / 2), (0.035 * s, w, toe_h / 2))],
                   hinge(f"{pre}_toe", "y", -60, 40, t("toe")))
    b.site("root", "pelvis", (0.0, 0.0, 0.0))
    return b


def humanoid_joint_map(toes: bool = True) -> JointMap:
    """Identity mapping onto a body built by :func:`build_humanoid` (collars folded in)."""
    links: dict[str, JointLink] = {
        "spine": JointLink(human=("spine", "spine1")),
        "chest": JointLink(human=("spine2",)),
        "neck": JointLink(human=("neck", "head")),
    }
    for side, pre in (("left", "l"), ("right", "r")):
        links[f"{pre}_shoulder"] = JointLink(human=(f"{side}_collar", f"{side}_shoulder"))
        links[f"{pre}_elbow"] = elbow_link(side)
        links[f"{pre}_wrist"] = JointLink(human=(f"{side}_wrist",))
        links[f"{pre}_hip"] = JointLink(human=(f"{side}_hip",))
        links[f"{pre}_knee"] = JointLink(human=(f"{side}_knee",))
        links[f"{pre}_ankle"] = JointLink(human=(f"{side}_ankle",))
        if toes:
            links[f"{pre}_toe"] = JointLink(human=(f"{side}_toe",))
    return JointMap(links=links)


def humanoid_groups(toes: bool = True) -> dict[str, tuple[str, ...]]:
    feet = ("l_foot", "r_foot", *(("l_toes", "r_toes") if toes else ()))
    return {
        "feet": feet,
        "contact": feet,
        "left_foot": ("l_foot", *(("l_toes",) if toes else ())),
        "right_foot": ("r_foot", *(("r_toes",) if toes else ())),
        "hands": ("l_hand", "r_hand"),
        # the contact reward's links (QuestEnvSim Sec. 3.3.2: feet, hands, pelvis, spine)
        "left_hand": ("l_hand",),
        "right_hand": ("r_hand",),
        "pelvis": ("pelvis",),
        "spine": ("abdomen", "chest"),
        "upper_body": ("pelvis", "abdomen", "chest", "head", "l_upper_arm", "r_upper_arm"),
        "lower_body": ("l_thigh", "r_thigh", "l_shin", "r_shin", *feet),
        "end_effectors": ("head", "l_hand", "r_hand", "l_foot", "r_foot"),
        # the 11 joints SimXR reports MPJPE on (head, shoulders, elbows, wrists, knees,
        # ankles), as the bodies whose origins sit at those joints
        "common_joints": (
            "head", "l_upper_arm", "r_upper_arm", "l_forearm", "r_forearm", "l_hand",
            "r_hand", "l_shin", "r_shin", "l_foot", "r_foot",
        ),
    }


LOWER_BODY_JOINTS = ("l_hip", "r_hip", "l_knee", "r_knee", "l_ankle", "r_ankle", "l_toe",
                     "r_toe")
