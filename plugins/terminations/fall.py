"""Falling (Sec. 3.6): the episode fails when the upper body touches the ground.

A body of the ``upper_body`` group counts as touching the ground when both hold:

* the normal contact force on it exceeds ``force_threshold`` (it touches *something*), and
* its origin is less than ``height_threshold`` above the ground under it (that something is
  the ground, not a chair back, a table or the character's own leg).

The ground height comes from the scene's ``height_at`` when the step has a scene, else the
floor at z = 0. Body origins sit inside the body, so the height threshold must exceed the
thickness of the character's torso and arms yet stay below their standing height. Letting the
built-in characters collapse with zero torque, the first upper-body touch happens with origins
at 0.25-0.27 m (human arms, Dino spine, Oppy head) and fallen bodies lie at 0.08-0.29 m, while
standing origins are at 0.96 m (human), 1.15 m (Dino) but only 0.25 m (Oppy's torso): the 0.3 m
default suits human and Dino; Oppy's recipe should lower it (about 0.2 m) so that a standing
Oppy whose arm brushes its own torso is not counted as fallen.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from pydantic import Field

import retarget
from retarget import Layout, PluginConfig, StepContext, Termination

if TYPE_CHECKING:
    import torch


class FallConfig(PluginConfig):
    force_threshold: float = Field(1.0, ge=0, description="newtons above which a body touches")
    height_threshold: float = Field(
        0.3, gt=0, description="metres above the ground below which a touching body has fallen"
    )


class Fall(Termination[FallConfig]):
    """Fails an episode when any upper-body body touches the ground (force and height test)."""

    name = "fall"
    requires = ("body_group:upper_body",)

    def bind(self, layout: Layout) -> None:
        import torch
        self._bodies = torch.tensor(layout.group("upper_body"), dtype=torch.long)

    def check(self, ctx: StepContext) -> torch.Tensor:
        pos = ctx.sim.body_pos[:, self._bodies]  # (N, K, 3)
        ground = ctx.scene.height_at(pos[..., :2])
        low = (pos[..., 2] - ground) < self.config.height_threshold
        touching = ctx.sim.contact_force[:, self._bodies] > self.config.force_threshold
        return (low & touching).any(dim=-1)


@retarget.hookimpl
def register_terminations(register) -> None:
    register(Fall)
