"""``boxbot``: a 1.53 m blocky robot (box torso and feet, capsule limbs), 13 links, 26 DoF.

Built with the public character builder (``retarget.character.builder``): bodies are placed
in the canonical T-pose (arms out along +-Y, +X forward, Z up), so the human's local joint
rotations map onto its joints through a plain joint map.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence

from pydantic import Field

import retarget
from retarget.character.builder import (
    BodyBuilder,
    Box,
    Capsule,
    Sphere,
    ball,
    hinge,
    joint,
)
from retarget.character.joint_map import JointLink, JointMap


class BoxbotConfig(retarget.PluginConfig):
    mass: float = Field(45.0, gt=5.0, le=300.0, description="total mass, kg")
    max_torque: float = Field(200.0, gt=0.0, le=2000.0, description="hip and spine torque, N m")


class Boxbot(retarget.Character[BoxbotConfig]):
    """A blocky robot: box torso and feet, capsule limbs, ball hips, shoulders and spine."""

    name = "boxbot"

    def build_spec(self):
        c = self.config
        t = c.max_torque
        b = BodyBuilder("boxbot", rgba=(0.55, 0.6, 0.65, 1.0))
        b.root("pelvis", (0, 0, 0.8), [Box((0, 0, 0), (0.1, 0.14, 0.06))])
        b.site("root", "pelvis", (0, 0, 0))
        b.body("torso", "pelvis", (0, 0, 0.08), [Box((0, 0, 0.2), (0.1, 0.16, 0.2))],
               ball("spine", (-30, 30), (-30, 60), (-40, 40), t, order="yzx"))
        b.body("head", "torso", (0, 0, 0.42), [Sphere((0, 0, 0.12), 0.11)],
               ball("neck", (-40, 40), (-45, 45), (-70, 70), 0.25 * t, order="yzx"))
        b.site("head", "head", (0.06, 0, 0.12))
        for side, sgn in (("left", 1.0), ("right", -1.0)):
            p = side[0]
            b.body(f"{p}_upper_arm", "torso", (0, sgn * 0.2, 0.34),
                   [Capsule((0, 0, 0), (0, sgn * 0.26, 0), 0.04)],
                   ball(f"{p}_shoulder", (-120, 120), (-100, 100), (-100, 100), 0.4 * t))
            b.body(f"{p}_forearm", f"{p}_upper_arm", (0, sgn * 0.28, 0),
                   [Capsule((0, 0, 0), (0, sgn * 0.24, 0), 0.035)],
                   hinge(f"{p}_elbow", "z", *((-150, 5) if sgn > 0 else (-5, 150)), 0.25 * t))
            b.site(f"{side}_hand", f"{p}_forearm", (0, sgn * 0.27, 0))
            b.body(f"{p}_thigh", "pelvis", (0, sgn * 0.09, -0.06),
                   [Capsule((0, 0, 0), (0, 0, -0.33), 0.06)],
                   ball(f"{p}_hip", (-40, 40), (-120, 40), (-45, 45), t))
            b.body(f"{p}_shin", f"{p}_thigh", (0, 0, -0.36),
                   [Capsule((0, 0, 0), (0, 0, -0.3), 0.05)],
                   hinge(f"{p}_knee", "y", -5, 150, 0.8 * t))
            b.body(f"{p}_foot", f"{p}_shin", (0, 0, -0.33),
                   [Box((0.04, 0, -0.03), (0.1, 0.05, 0.025))],
                   joint(f"{p}_ankle", {"y": (-45, 45), "x": (-30, 30)}, 0.4 * t))
        return b.build(mass=c.mass).spec

    def body_groups(self) -> Mapping[str, Sequence[str]]:
        return {
            "feet": ("l_foot", "r_foot"),
            "upper_body": ("torso", "head", "l_upper_arm", "r_upper_arm"),
        }

    def joint_map(self) -> JointMap:
        """Each robot joint follows the human joint(s) of the same place."""
        links = {
            "spine": JointLink(human=("spine", "spine1", "spine2")),
            "neck": JointLink(human=("neck", "head")),
        }
        for side in ("left", "right"):
            p = side[0]
            links[f"{p}_shoulder"] = JointLink(human=(f"{side}_collar", f"{side}_shoulder"))
            links[f"{p}_elbow"] = JointLink(human=(f"{side}_elbow",))
            links[f"{p}_hip"] = JointLink(human=(f"{side}_hip",))
            links[f"{p}_knee"] = JointLink(human=(f"{side}_knee",))
            links[f"{p}_ankle"] = JointLink(human=(f"{side}_ankle",))
        return JointMap(links=links)


@retarget.hookimpl
def register_characters(register) -> None:
    register(Boxbot)
