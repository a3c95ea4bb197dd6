"""Link imitation (App. A, Eq. 11): chosen bodies follow the reference in Cartesian space.

``bodies`` picks what is tracked: group names (``end_effectors``, ``feet``, ...), body names,
or ``root`` for the body carrying the free joint; ``None`` tracks every body. The paper tracks
only the root for Oppy and Dino (``bodies: [root]``) and the root plus end effectors for Jesse
(``bodies: [root, end_effectors]``); those belong in the character's recipe, while the plugin
default (all bodies) works for any character.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from pydantic import Field
from typing_extensions import TypeVar

import retarget
from retarget import Layout, RewardConfig, RewardTerm, StepContext, gaussian_kernel
from retarget.plugins.rewards.common import Reduce, resolve_bodies, weighted_sq_distance

if TYPE_CHECKING:
    import torch

_BODIES = "group names, body names or 'root'; null tracks every body"
_RELATIVE = (
    "subtract the root body's value from every body (sim from sim, reference from reference), "
    "so only the shape of the pose counts and a drifting root is left to the root term"
)


class LinkTermConfig(RewardConfig):
    """What both link terms select and how they sum."""

    bodies: list[str] | None = Field(None, description=_BODIES)
    root_relative: bool = Field(False, description=_RELATIVE)
    reduce: Reduce = Field("sum", description="sum over bodies (paper) or mean")


LinkConfigT = TypeVar("LinkConfigT", bound=LinkTermConfig, default=LinkTermConfig)


class LinkPosConfig(LinkTermConfig):
    weight: float = 2.5
    k: float = Field(6.0, gt=0, description="kernel sensitivity on the squared distance, 1/m^2")


class _LinkTerm(RewardTerm[LinkConfigT]):
    """Shared body selection and distance of the two link terms."""

    def bind(self, layout: Layout) -> None:
        import torch
        self._idx = resolve_bodies(layout, self.config.bodies, self.name)
        self._weights = torch.ones(len(self._idx), dtype=torch.float32)

    def _distance(self, sim: torch.Tensor, ref: torch.Tensor) -> torch.Tensor:
        if self.config.root_relative:
            sim = sim - sim[:, :1]
            ref = ref - ref[:, :1]
        diff = sim[:, self._idx] - ref[:, self._idx]
        return weighted_sq_distance(diff, self._weights, self.config.reduce)


class LinkPos(_LinkTerm[LinkPosConfig]):
    """Body positions follow the reference: exp(-k * sum_b ||x_sim,b - x_ref,b||^2).

    Table 2: Jesse (the default) w=2.5, k=6 with root and end effectors; Oppy and Dino w=1, k=6
    with the root only.
    """

    name = "link_pos"

    def compute(self, ctx: StepContext) -> torch.Tensor:
        d = self._distance(ctx.sim.body_pos, ctx.ref.pose.body_pos)
        return gaussian_kernel(d, self.config.k).float()


class LinkVelConfig(LinkTermConfig):
    weight: float = 0.7
    k: float = Field(2.0, gt=0, description="kernel sensitivity on the squared error, s^2/m^2")


class LinkVel(_LinkTerm[LinkVelConfig]):
    """Body linear velocities follow the reference: exp(-k * sum_b ||v_sim,b - v_ref,b||^2).

    Table 2: Jesse (the default) w=0.7, k=2; Oppy and Dino do not use it (w=0).
    """

    name = "link_vel"

    def compute(self, ctx: StepContext) -> torch.Tensor:
        d = self._distance(ctx.sim.body_linvel, ctx.ref.pose.body_linvel)
        return gaussian_kernel(d, self.config.k).float()


@retarget.hookimpl
def register_rewards(register) -> None:
    register(LinkPos)
    register(LinkVel)
