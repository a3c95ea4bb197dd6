"""``human``: the canonical human skeleton as a simulated body, scaled to the user's height."""

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


class HumanConfig(CharacterConfig):
    height: float = Field(1.75, gt=0.5, le=2.5, description="standing height, floor to crown, m")
    mass: float | None = Field(
        None, gt=10.0, le=300.0,
        description="total mass, kg; default from a body-mass index of 22.9 (70 kg at 1.75 m)")
    max_torque: float = Field(300.0, gt=0.0, description="torque limit before per-joint scales")


class Human(ProceduralCharacter[HumanConfig]):
    """A human avatar on the canonical skeleton's proportions (18 links, 35 DoF).

    QuestEnvSim's avatar has 18 links and 32 DoF without a published split; ours has 3-DoF
    abdomen, chest, neck, shoulders and hips, 2-DoF wrists and ankles, 1-DoF elbows, knees and
    toes (35), so the controller orientation and the foot roll of the mocap are kept.

    Like the QuestEnvSim avatar: capsules/boxes/spheres of uniform density, torque actuated,
    no self-collision. Joint centres are the canonical T-pose joints at the configured height,
    so kinematic retargeting of a human clip is exact up to the folded collar and spine joints.
    Torque scales are Jesse's (Table 4 of the paper).
    """

    name = "human"
    lower_body_joints = LOWER_BODY_JOINTS

    @property
    def target_mass(self) -> float:
        h = self.config.height
        return self.config.mass if self.config.mass is not None else 22.9 * h * h

    def describe(self) -> BodyBuilder:
        return build_humanoid("human", self.config.height, self.config.max_torque,
                              HumanoidShape())

    def default_joint_map(self) -> JointMap:
        return humanoid_joint_map(toes=True)

    def body_groups(self) -> Mapping[str, Sequence[str]]:
        return humanoid_groups(toes=True)


@retarget.hookimpl
def register_characters(register) -> None:
    register(Human)
