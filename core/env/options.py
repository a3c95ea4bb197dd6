"""The tracking environment's own settings: the recipe's ``env`` section, used as is."""

from __future__ import annotations

from typing import Annotated

from pydantic import BaseModel, ConfigDict, Field

from retarget.env.curriculum import CurriculumOptions
from retarget.env.root_assist import RootAssistOptions


class EnvOptions(BaseModel):
    """Environment settings that are not plugins (plugins configure the rest)."""

    model_config = ConfigDict(extra="forbid", frozen=True, allow_inf_nan=False)

    num_envs: int = Field(256, ge=1, le=65536, description="environments stepped together")
    privileged_offsets: tuple[Annotated[int, Field(ge=1, le=3600)], ...] = Field(
        (1, 3, 6),
        max_length=64,
        description="future reference frames the critic sees (asymmetric critic)",
    )
    reset_lift: float = Field(
        0.02, ge=0, le=1, description="root lift at reset, m (kinematic feet penetrate a bit)"
    )
    groups: dict[str, list[str]] | None = Field(
        None,
        description="observation groups: name -> sources (sensor/observer names, 'proprio', "
        "'privileged'); default actor = sensors + proprio + observers, critic = actor + "
        "privileged",
    )
    curriculum: CurriculumOptions | None = Field(
        None,
        description="start episodes where recent failures happened, with a uniform share "
        "(null: frame-uniform starts); e.g. {uniform: 0.5, bin_seconds: 2}",
    )
    root_assist: RootAssistOptions | None = Field(
        None,
        description="training only: a root force/torque toward the reference, annealed to "
        "zero over anneal_steps (null: none); e.g. {strength: 1, anneal_steps: 3000000}",
    )
