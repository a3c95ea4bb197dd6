"""Joint imitation (App. A, Eq. 11): the simulated hinges follow the kinematic reference.

Both terms compare the hinge joints after the free root (``qpos[:, 7:]``, ``qvel[:, 6:]``)
with the retargeted pose, weighted per joint by the character (``Layout.joint_weights``: the
paper sets lower-body joints of Oppy and Dino to 0.3, passive tails and ears to 0, everything
of Jesse to 1).
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

from pydantic import Field

import retarget
from retarget import Layout, RewardConfig, RewardTerm, StepContext, gaussian_kernel
from retarget.plugins.rewards.common import Reduce, joint_weight_tensor, weighted_sq_distance

if TYPE_CHECKING:
    import torch


class JointPosConfig(RewardConfig):
    weight: float = 4.0
    k: float = Field(25.0, gt=0, description="kernel sensitivity on the weighted squared error")
    reduce: Reduce = Field("sum", description="sum over joints (paper) or weight-normalised mean")


class JointPos(RewardTerm[JointPosConfig]):
    """Joint angles follow the reference: exp(-k * sum_j w_j (q_sim,j - q_ref,j)^2).

    Angle differences are wrapped to [-pi, pi) so an unlimited hinge that went once around is
    not punished. Table 2: Jesse (the default) w=4, k=25; Oppy and Dino w=1, k=20.
    """

    name = "joint_pos"

    def bind(self, layout: Layout) -> None:
        self._weights = joint_weight_tensor(layout, self.name)

    def compute(self, ctx: StepContext) -> torch.Tensor:
        import torch
        diff = ctx.sim.qpos[:, 7:] - ctx.ref.pose.qpos[:, 7:]
        diff = torch.remainder(diff + math.pi, 2 * math.pi) - math.pi
        d = weighted_sq_distance(diff, self._weights, self.config.reduce)
        return gaussian_kernel(d, self.config.k).float()


class JointVelConfig(RewardConfig):
    weight: float = 0.5
    k: float = Field(1.0, gt=0, description="kernel sensitivity on the weighted squared error")
    reduce: Reduce = Field("sum", description="sum over joints (paper) or weight-normalised mean")


class JointVel(RewardTerm[JointVelConfig]):
    """Joint velocities follow the reference: exp(-k * sum_j w_j (dq_sim,j - dq_ref,j)^2).

    Uses the same per-joint weights as ``joint_pos``. Table 2: Jesse (the default) w=0.5, k=1;
    Oppy and Dino do not use it (w=0).
    """

    name = "joint_vel"

    def bind(self, layout: Layout) -> None:
        self._weights = joint_weight_tensor(layout, self.name)

    def compute(self, ctx: StepContext) -> torch.Tensor:
        diff = ctx.sim.qvel[:, 6:] - ctx.ref.pose.qvel[:, 6:]
        d = weighted_sq_distance(diff, self._weights, self.config.reduce)
        return gaussian_kernel(d, self.config.k).float()


@retarget.hookimpl
def register_rewards(register) -> None:
    register(JointPos)
    register(JointVel)
