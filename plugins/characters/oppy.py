"""``oppy``: the paper's mouse-like creature (7 kg, 80 cm, big head, passive tail and ears)."""

from __future__ import annotations

from collections.abc import Mapping, Sequence

from pydantic import Field

import retarget
from retarget.character.builder import BodyBuilder, Box, Capsule, Ellipsoid, Sphere, ball, joint
from retarget.character.joint_map import JointLink, JointMap, elbow_link

from .common import CharacterConfig, ProceduralCharacter, scaled

REFERENCE_HEIGHT = 0.8
"""Height (floor to ear tips) the geometry below is written at; it scales with the config."""

TORQUE_SCALES: Mapping[str, float] = {
    "spine": 1.0, "neck": 0.1, "shoulder": 0.2, "elbow": 0.1, "hip": 1.0, "knee": 1.0,
    "ankle": 1.0,
}
"""Table 4 (Oppy column)."""

EAR_SEGMENTS = 4
TAIL_SEGMENTS: tuple[tuple[float, float], ...] = ((0.1, 0.018), (0.1, 0.014), (0.1, 0.01))


class OppyConfig(CharacterConfig):
    height: float = Field(0.8, gt=0.1, le=3.0,
                          description="standing height, floor to ear tips, m")
    mass: float = Field(7.0, gt=0.1, le=200.0, description="total mass, kg")
    max_torque: float = Field(40.0, gt=0.0, description="torque limit before Table 4 scales")
    ear_frequency: float = Field(3.0, gt=0.0, description="ears' natural frequency, Hz")
    ear_damping_ratio: float = Field(0.1, gt=0.0, description="ears' damping ratio")
    tail_frequency: float = Field(2.0, gt=0.0, description="tail's natural frequency, Hz")
    tail_damping_ratio: float = Field(0.15, gt=0.0, description="tail's damping ratio")


class Oppy(ProceduralCharacter[OppyConfig]):
    """Oppy: a mouse-like creature with a short lower body, a big head, big ears and a tail.

    Table 1: 7 kg, 80 cm, 24 links (pelvis, torso, head, 2x upper arm, forearm = 7 upper; 2x
    thigh, shin, foot = 6 lower; 3 tail; 2x4 ear), 58 DoF: torso, neck, shoulders and hips
    3-DoF, elbows 2 (bend, twist), knees 1, ankles 2; tail segments 2 (yaw, pitch) and ear
    segments 3, all passive spring-dampers without actuators. Lower-body joint weight 0.3
    (App. A); torque scales Table 4 with max torque 40.
    """

    name = "oppy"
    lower_body_joints = ("l_hip", "r_hip", "l_knee", "r_knee", "l_ankle", "r_ankle")
    lower_body_weight = 0.3

    def describe(self) -> BodyBuilder:
        cfg = self.config
        s = cfg.height / REFERENCE_HEIGHT

        def v(x: float, y: float, z: float) -> tuple[float, float, float]:
            return scaled((x, y, z), s)

        def t(fam: str) -> float:
            return cfg.max_torque * TORQUE_SCALES[fam]

        # Damping 0.025 N m s/rad per N m (terminal speed 40 rad/s): a 7 kg body with 40 N m
        # hips otherwise reaches joint limits fast enough to go unstable under random torques.
        b = BodyBuilder("oppy", rgba=(0.62, 0.6, 0.66, 1.0), damping_per_nm=0.025)
        pink = (0.95, 0.68, 0.72, 1.0)
        b.root("pelvis", v(0, 0, 0.2), [Ellipsoid((0, 0, 0), v(0.075, 0.085, 0.06))])
        b.site("root", "pelvis", (0.0, 0.0, 0.0))
        b.body("torso", "pelvis", v(0, 0, 0.05), [Ellipsoid(v(0, 0, 0.07), v(0.08, 0.085, 0.1))],
               ball("spine", (-30, 30), (-30, 50), (-45, 45), t("spine"), order="yzx"))
        b.body("head", "torso", v(0, 0, 0.17),
               [Sphere(v(0.02, 0, 0.13), 0.15 * s), Sphere(v(0.15, 0, 0.09), 0.05 * s)],
               ball("neck", (-40, 40), (-45, 50), (-70, 70), t("neck"), order="yzx"))
        b.site("head", "head", v(0.16, 0, 0.16))  # headset at the eyes

        for side, sgn, pre in (("left", 1.0, "l"), ("right", -1.0, "r")):
            b.body(f"{pre}_upper_arm", "torso", v(0, sgn * 0.085, 0.12),
                   [Capsule(v(0, sgn * 0.015, 0), v(0, sgn * 0.08, 0), 0.024 * s)],
                   ball(f"{pre}_shoulder", (-120, 170) if sgn > 0 else (-170, 120), (-90, 90),
                        (-150, 80) if sgn > 0 else (-80, 150), t("shoulder"), order="xyz"))
            b.body(f"{pre}_forearm", f"{pre}_upper_arm", v(0, sgn * 0.09, 0),
                   [Capsule(v(0, sgn * 0.01, 0), v(0, sgn * 0.07, 0), 0.02 * s),
                    Sphere(v(0, sgn * 0.09, 0), 0.028 * s)],
                   joint(f"{pre}_elbow", {"z": (-150, 5) if sgn > 0 else (-5, 150),
                                          "y": (-90, 90)}, t("elbow")))
            b.site(f"{side}_hand", f"{pre}_forearm", v(0, sgn * 0.09, 0))

            b.body(f"{pre}_thigh", "pelvis", v(0, sgn * 0.05, -0.03),
                   [Capsule((0, 0, 0), v(0, 0, -0.06), 0.035 * s)],
                   ball(f"{pre}_hip", (-35, 60) if sgn > 0 else (-60, 35), (-120, 40), (-45, 45),
                        t("hip"), order="yzx"))
            b.body(f"{pre}_shin", f"{pre}_thigh", v(0, 0, -0.07),
                   [Capsule((0, 0, 0), v(0, 0, -0.055), 0.028 * s)],
                   joint(f"{pre}_knee", {"y": (-5, 150)}, t("knee")))
            b.body(f"{pre}_foot", f"{pre}_shin", v(0, 0, -0.065),
                   [Box(v(0.03, 0, -0.02), v(0.065, 0.035, 0.015))],
                   joint(f"{pre}_ankle", {"y": (-50, 50), "x": (-30, 30)}, t("ankle")),
                   rgba=pink)

            # Ears: four flat segments rising from the top of the head, each a passive 3-DoF
            # spring-damper, so they flop with head motion (secondary motion, Sec. 4.4).
            parent, pos = "head", v(-0.02, sgn * 0.09, 0.24)
            for k in range(EAR_SEGMENTS):
                name = f"{pre}_ear{k}"
                b.body(name, parent, pos,
                       [Ellipsoid(v(0, sgn * 0.012, 0.015), v(0.012, 0.058, 0.04))],
                       ball(name, (-40, 40), (-40, 40), (-30, 30), order="xyz",
                            frequency=cfg.ear_frequency, damping_ratio=cfg.ear_damping_ratio),
                       rgba=pink)
                parent, pos = name, v(0, sgn * 0.022, 0.03)

        parent, pos = "pelvis", v(-0.07, 0, -0.02)
        for i, (length, radius) in enumerate(TAIL_SEGMENTS):
            end = v(-length, 0, 0.15 * length)
            b.body(f"tail{i}", parent, pos, [Capsule((0, 0, 0), end, radius * s)],
                   joint(f"tail{i}", {"z": (-45, 45), "y": (-45, 45)},
                         frequency=cfg.tail_frequency, damping_ratio=cfg.tail_damping_ratio),
                   rgba=pink)
            parent, pos = f"tail{i}", end
        return b

    def default_joint_map(self) -> JointMap:
        links = {
            "spine": JointLink(human=("spine", "spine1", "spine2")),
            "neck": JointLink(human=("neck", "head")),
        }
        for side, pre in (("left", "l"), ("right", "r")):
            links[f"{pre}_shoulder"] = JointLink(human=(f"{side}_collar", f"{side}_shoulder"))
            links[f"{pre}_elbow"] = elbow_link(side, twist=True)
            links[f"{pre}_hip"] = JointLink(human=(f"{side}_hip",))
            links[f"{pre}_knee"] = JointLink(human=(f"{side}_knee",))
            links[f"{pre}_ankle"] = JointLink(human=(f"{side}_ankle",))
        return JointMap(links=links)

    def body_groups(self) -> Mapping[str, Sequence[str]]:
        feet = ("l_foot", "r_foot")
        ears = tuple(f"{p}_ear{k}" for p in ("l", "r") for k in range(EAR_SEGMENTS))
        return {
            "feet": feet,
            "contact": feet,
            "left_foot": ("l_foot",),
            "right_foot": ("r_foot",),
            "hands": ("l_forearm", "r_forearm"),
            "left_hand": ("l_forearm",),
            "right_hand": ("r_forearm",),
            "pelvis": ("pelvis",),
            "spine": ("torso",),
            "upper_body": ("torso", "head", "l_upper_arm", "r_upper_arm"),
            "lower_body": ("pelvis", "l_thigh", "r_thigh", "l_shin", "r_shin", *feet),
            "tail": tuple(f"tail{i}" for i in range(len(TAIL_SEGMENTS))),
            "ears": ears,
            "end_effectors": ("head", "l_forearm", "r_forearm", "l_foot", "r_foot"),
        }


@retarget.hookimpl
def register_characters(register) -> None:
    register(Oppy)
