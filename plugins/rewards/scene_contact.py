"""Scene contact (QuestEnvSim Eq. 3): the avatar touches the scene where the reference does.

``r = exp(-k * ||c_sim - c_ref||)`` with ``c`` a multi-hot vector over contact links: by
default the body groups ``left_foot``, ``right_foot``, ``left_hand``, ``right_hand``,
``pelvis`` and ``spine`` (the paper's feet, hands, root and spine). The norm is the paper's
Euclidean norm (not squared), so for 0/1 vectors ``d = sqrt(#mismatches)``.

``c_ref`` are the reference's scene contact labels (``ctx.ref.scene_contacts``): collision
checks of the kinematic reference against the un-randomized scene, computed once per library
frame (:mod:`retarget.scene.contacts`). ``c_sim``: a group is in contact when the contact
force on its bodies (summed: a foot split into heel and toes is one link) exceeds
``force_threshold``. The paper "ignores contacts of magnitudes lower than 50 N in the gravity
(i.e. upward) direction", read here literally as the default ``measure="up"``: the upward (+Z)
component of the net contact force, i.e. a link counts when it carries at least 50 N of
weight. Sideways pushes (a hand on a wall, a back against an upright backrest) then never
count; ``measure="total"`` thresholds the force's magnitude instead. 50 N suits human-sized
avatars (a 70 kg human's foot carries ~340 N); scale it down for small ones (Oppy weighs 69 N).
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Literal

from pydantic import Field

import retarget
from retarget import (
    Layout,
    PluginError,
    RewardConfig,
    RewardTerm,
    StepContext,
    StepNeeds,
    gaussian_kernel,
)
from retarget.scene.contacts import CONTACT_LINKS as LINKS
from retarget.scene.contacts import CONTACT_NEWTONS

if TYPE_CHECKING:
    import torch


class SceneContactConfig(RewardConfig):
    k: float = Field(1.0, gt=0, description="kernel sensitivity k_c on ||c_sim - c_ref||")
    force_threshold: float = Field(
        CONTACT_NEWTONS, ge=0, description="newtons a link's contact force must exceed (paper: 50)"
    )
    measure: Literal["up", "total"] = Field(
        "up", description="threshold the upward component (paper) or the force's magnitude"
    )
    groups: tuple[str, ...] = Field(
        LINKS, min_length=1, description="body groups that make up the contact state"
    )


class SceneContact(RewardTerm[SceneContactConfig]):
    """Multi-hot contact of feet, hands, pelvis and spine matches the scene labels (Eq. 3)."""

    name = "contact"
    requires = tuple(f"body_group:{g}" for g in LINKS)

    def bind(self, layout: Layout) -> None:
        import torch
        groups = list(layout.body_groups)
        missing = [g for g in self.config.groups if g not in layout.body_groups]
        if missing:
            raise PluginError(
                f"groups {missing} are not body groups of the character "
                f"(it has: {', '.join(groups)})",
                plugin=self.name,
                field="groups",
            )
        bodies = sorted({i for g in self.config.groups for i in layout.group(g)})
        # (K, G): body k belongs to contact group g, so a matrix product sums groups' forces
        member = torch.zeros(len(bodies), len(self.config.groups))
        for j, g in enumerate(self.config.groups):
            for i in layout.group(g):
                member[bodies.index(i), j] = 1.0
        self._bodies = torch.tensor(bodies, dtype=torch.long)
        self._member = member
        self._columns = torch.tensor([groups.index(g) for g in self.config.groups])

    def needs(self) -> StepNeeds:
        return StepNeeds(scene_contacts=True)

    def sim_contacts(self, ctx: StepContext) -> torch.Tensor:
        """``(N, G)`` bool: each configured group's contact state in the simulation."""
        sim = ctx.sim
        force = sim.contact_force_up if self.config.measure == "up" else sim.contact_force
        return force[:, self._bodies] @ self._member > self.config.force_threshold

    def compute(self, ctx: StepContext) -> torch.Tensor:
        labels = ctx.ref.scene_contacts
        if labels is None:
            raise PluginError(
                "the step context has no scene contact labels (ctx.ref.scene_contacts)",
                plugin=self.name,
                hint="the environment gathers them for terms whose needs() asks",
            )
        ref = labels[:, self._columns]
        mismatches = (self.sim_contacts(ctx) != ref).float().sum(-1)
        return gaussian_kernel(mismatches.sqrt(), self.config.k).float()


@retarget.hookimpl
def register_rewards(register) -> None:
    register(SceneContact)
