"""Drifting (Sec. 3.6): the episode fails when the root strays from the reference root.

The reference root is the kinematically retargeted one, already scaled to the character's size,
so the same threshold serves every character. Far from its reference the imitation rewards are
near zero and teach nothing; ending the episode (with the fail penalty) is the useful signal.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from pydantic import Field

import retarget
from retarget import PluginConfig, StepContext, Termination

if TYPE_CHECKING:
    import torch


class RootDistanceConfig(PluginConfig):
    max_distance: float = Field(0.3, gt=0, description="metres between sim and reference root")
    horizontal: bool = Field(False, description="measure in the ground plane only (ignore z)")


class RootDistance(Termination[RootDistanceConfig]):
    """Fails an episode when the root is over ``max_distance`` (0.3 m) from the reference root."""

    name = "root_distance"

    def check(self, ctx: StepContext) -> torch.Tensor:
        dims = 2 if self.config.horizontal else 3
        diff = ctx.sim.qpos[:, :dims] - ctx.ref.pose.qpos[:, :dims]
        return diff.square().sum(dim=-1) > self.config.max_distance**2


@retarget.hookimpl
def register_terminations(register) -> None:
    register(RootDistance)
