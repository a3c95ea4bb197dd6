"""A complete third-party retarget plugin: one reward term, registered through an entry point.

Install it (``pip install .``) and ``retarget plugins`` lists ``head_height``; a recipe can then
say ``rewards: {head_height: {weight: 0.2}}``.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from pydantic import Field

import retarget

if TYPE_CHECKING:
    import torch


class HeadHeightConfig(retarget.RewardConfig):
    weight: float = 0.1
    k: float = Field(20.0, gt=0, description="kernel sensitivity per metre of height error")


class HeadHeight(retarget.RewardTerm[HeadHeightConfig]):
    """Rewards keeping the headset at the reference height: exp(-k * |z_sim - z_ref|).

    Useful for crouching and sitting clips, where horizontal tracking alone lets the character
    stand up straight.
    """

    name = "head_height"
    requires = ("site:head",)

    def bind(self, layout: retarget.Layout) -> None:
        self.head = layout.site("head")  # resolved once, indexed every step

    def compute(self, ctx: retarget.StepContext) -> torch.Tensor:
        z_sim = ctx.sim.site_pos[:, self.head, 2]
        z_ref = ctx.ref.pose.site_pos[:, self.head, 2]
        return retarget.gaussian_kernel((z_sim - z_ref).abs(), self.config.k).float()


@retarget.hookimpl
def register_rewards(register) -> None:
    register(HeadHeight)
