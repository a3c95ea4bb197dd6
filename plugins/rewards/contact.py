"""Foot contact (Sec. 3.5.2): the simulated feet touch the ground when the human's do.

The simulated foot is in contact when the normal force on it exceeds ``force_threshold``
(1 N in App. A); the human's labels come with the reference (``ref.contacts``, from foot height
and speed). Labels are matched in one of two layouts, chosen from their count:

* one label per body of the ``feet`` group: each body is compared with its own label;
* two labels (left, right foot of the human), with ``left_foot``/``right_foot`` body groups: a
  side is in contact when any of its bodies is (a heel or toe touching both count).

The distance is the number of mismatching labels, the squared Euclidean distance between the
two 0/1 vectors (``normalize=true`` divides by the count, so ``k`` means the same for two feet
and four foot bodies).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from pydantic import Field

import retarget
from retarget import Layout, PluginError, RewardConfig, RewardTerm, StepContext, gaussian_kernel

if TYPE_CHECKING:
    import torch


class FootContactConfig(RewardConfig):
    weight: float = 0.0
    k: float = Field(1.0, gt=0, description="kernel sensitivity on the mismatch count")
    force_threshold: float = Field(1.0, ge=0, description="newtons above which a foot touches")
    normalize: bool = Field(False, description="use the fraction of mismatches, not the count")


class FootContact(RewardTerm[FootContactConfig]):
    """Simulated foot contacts match the human's labels: exp(-k * #mismatches).

    Table 2: Oppy and Dino w=1.5, k=1; Jesse (the default) w=0, i.e. off, since its imitation
    terms already pin the legs. Set ``weight: 1.5`` in a recipe to use it.
    """

    name = "foot_contact"
    requires = ("body_group:feet",)

    def bind(self, layout: Layout) -> None:
        import torch
        feet = layout.group("feet")
        self._feet = torch.tensor(feet, dtype=torch.long)
        self._sides: torch.Tensor | None = None
        if "left_foot" in layout.body_groups and "right_foot" in layout.body_groups:
            left, right = layout.group("left_foot"), layout.group("right_foot")
            self._side_bodies = torch.tensor([*left, *right], dtype=torch.long)
            # (2, K) membership: row 0 the left foot's bodies, row 1 the right foot's.
            sides = torch.zeros(2, len(left) + len(right))
            sides[0, : len(left)] = 1.0
            sides[1, len(left) :] = 1.0
            self._sides = sides

    def _sim_contacts(self, ctx: StepContext, count: int) -> torch.Tensor:
        force = ctx.sim.contact_force
        if count == len(self._feet):
            return force[:, self._feet] > self.config.force_threshold
        if count == 2 and self._sides is not None:
            touching = (force[:, self._side_bodies] > self.config.force_threshold).float()
            return (touching @ self._sides.T) > 0.5
        raise PluginError(
            f"{count} reference contact labels match neither the {len(self._feet)} bodies of "
            "group 'feet' nor two sides with groups 'left_foot'/'right_foot'",
            plugin=self.name,
        )

    def compute(self, ctx: StepContext) -> torch.Tensor:
        labels = ctx.ref.contacts
        sim = self._sim_contacts(ctx, labels.shape[1])
        d = (sim != labels.bool()).float().sum(dim=-1)
        if self.config.normalize:
            d = d / max(labels.shape[1], 1)
        return gaussian_kernel(d, self.config.k).float()


@retarget.hookimpl
def register_rewards(register) -> None:
    register(FootContact)
