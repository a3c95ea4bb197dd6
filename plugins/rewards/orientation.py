"""Orientation imitation (Sec. 3.5.1): root and head turn like the human's.

The paper matches the character's root and head orientation with the *human* root and head,
not with the retargeted pose, because orientations do not depend on the skeleton. Kinematic
retargeting copies the human root rotation onto the character root and drives the head from the
human head, so the reference pose's root (``ref.pose.qpos[:, 3:7]``) and ``head`` site carry the
human orientations; this term reads them there.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from pydantic import Field

import retarget
from retarget import Layout, RewardConfig, RewardTerm, StepContext, gaussian_kernel

if TYPE_CHECKING:
    import torch


class OrientationConfig(RewardConfig):
    weight: float = 2.0
    k: float = Field(3.0, gt=0, description="kernel sensitivity on the summed angles, 1/rad")
    root_weight: float = Field(1.0, ge=0, description="weight of the root's angle error")
    head_weight: float = Field(1.0, ge=0, description="weight of the head site's angle error")


class Orientation(RewardTerm[OrientationConfig]):
    """Root and head orientation follow the human: exp(-k * (w_r d_root + w_h d_head)).

    Each distance is the axis-angle norm of ``q_ref * q_sim^-1`` in radians (App. A). Table 2:
    w=2, k=3 for Jesse (the default); w=1, k=3 for Oppy and Dino.
    """

    name = "orientation"
    requires = ("site:head",)

    def bind(self, layout: Layout) -> None:
        import torch
        self._head = layout.site("head")
        self._weights = torch.tensor(
            [self.config.root_weight, self.config.head_weight], dtype=torch.float32
        )

    def compute(self, ctx: StepContext) -> torch.Tensor:
        import torch

        from retarget.geometry.heading import rotation_distance
        h = self._head
        # root and head in one (N, 2, 4) batch: one product and one atan2 for both
        ref = torch.stack([ctx.ref.pose.qpos[:, 3:7], ctx.ref.pose.site_quat[:, h]], dim=1)
        sim = torch.stack([ctx.sim.qpos[:, 3:7], ctx.sim.site_quat[:, h]], dim=1)
        d = (rotation_distance(ref, sim) * self._weights).sum(dim=-1)
        return gaussian_kernel(d, self.config.k).float()


@retarget.hookimpl
def register_rewards(register) -> None:
    register(Orientation)
