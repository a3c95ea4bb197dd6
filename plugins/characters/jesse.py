"""``jesse``: the paper's cartoon human (60 kg, 180 cm, 16 links, 32 DoF, max torque 300)."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import TYPE_CHECKING

from pydantic import Field

import retarget
from retarget.character.joint_map import JointMap

from .common import CharacterConfig, ProceduralCharacter
from .humanoid import (
    LOWER_BODY_JOINTS,
    HumanoidShape,
    build_humanoid,
    humanoid_groups,
    humanoid_joint_map,
)

if TYPE_CHECKING:
    from retarget.character.builder import BodyBuilder

# Cartoon proportions: slim limbs (60 kg at 1.8 m), a big head, big hands and feet.
JESSE_SHAPE = HumanoidShape(
    pelvis_r=0.08, abdomen_r=0.07, chest_r=0.095, neck_r=0.04, head_r=0.13,
    upper_arm_r=0.036, forearm_r=0.032, hand_half=(0.055, 0.08, 0.025), thigh_r=0.058,
    shin_r=0.045, foot_half_width=0.055, toes=False, chest_twist=False,
    rgba=(0.35, 0.55, 0.85, 1.0),
)


class JesseConfig(CharacterConfig):
    height: float = Field(1.80, gt=0.5, le=3.0, description="standing height, floor to crown, m")
    mass: float = Field(60.0, gt=5.0, le=300.0, description="total mass, kg")
    max_torque: float = Field(300.0, gt=0.0, description="torque limit before Table 4 scales")


class Jesse(ProceduralCharacter[JesseConfig]):
    """Jesse, a cartoon human with a skeleton close to the mocap's (paper Table 1).

    16 links (pelvis, abdomen, chest, head, upper arms, forearms, hands, thighs, shins, feet)
    and 32 DoF: abdomen 3, chest 2, neck 3, shoulders 3, elbows 1, wrists 2, hips 3, knees 1,
    ankles 2. All joint weights are 1 (App. A); torque scales from Table 4.
    """

    name = "jesse"
    lower_body_joints = LOWER_BODY_JOINTS
    lower_body_weight = 1.0

    def describe(self) -> BodyBuilder:
        return build_humanoid("jesse", self.config.height, self.config.max_torque, JESSE_SHAPE)

    def default_joint_map(self) -> JointMap:
        return humanoid_joint_map(toes=False)

    def body_groups(self) -> Mapping[str, Sequence[str]]:
        return humanoid_groups(toes=False)


@retarget.hookimpl
def register_characters(register) -> None:
    register(Jesse)
