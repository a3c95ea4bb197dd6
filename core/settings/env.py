"""The tracking environment's own settings: the recipe's ``env`` section, used as is
(with its ``curriculum``, ``root_assist`` and ``device_noise`` subsections)."""

from __future__ import annotations

from typing import Annotated, Literal

from pydantic import BaseModel, ConfigDict, Field


class CurriculumOptions(BaseModel):
    """The recipe's ``env.curriculum`` section."""

    model_config = ConfigDict(extra="forbid", frozen=True, allow_inf_nan=False)

    uniform: float = Field(0.5, ge=0.0, le=1.0,
                           description="share of starts drawn frame-uniformly")  # fmt: skip
    bin_seconds: float = Field(2.0, ge=0.1, le=60.0, description="segment length, s")
    half_life_steps: int = Field(
        2_000_000, ge=1000, le=10**12,
        description="environment steps after which a failure counts half",
    )  # fmt: skip


class RootAssistOptions(BaseModel):
    """The recipe's ``env.root_assist`` section."""

    model_config = ConfigDict(extra="forbid", frozen=True, allow_inf_nan=False)

    strength: float = Field(1.0, ge=0.0, le=10.0, description="scale at the start of training")
    anneal_steps: int = Field(
        3_000_000, ge=1, le=10**12, description="environment steps until the assist is zero"
    )
    frequency: float = Field(1.5, gt=0.0, le=10.0, description="PD natural frequency, Hz")
    damping_ratio: float = Field(1.0, ge=0.0, le=5.0, description="PD damping ratio")
    max_force: float = Field(1.0, gt=0.0, le=10.0, description="cap, times body weight")

    def scale_at(self, env_steps: int) -> float:
        return self.strength * max(0.0, 1.0 - env_steps / self.anneal_steps)


class DeviceNoiseOptions(BaseModel):
    """The recipe's ``env.device_noise`` section."""

    model_config = ConfigDict(extra="forbid", frozen=True, allow_inf_nan=False)

    height: float = Field(
        0.05, ge=0.0, le=0.5, description="half-range of an episode's vertical offset, m"
    )
    scale: float = Field(
        0.03, ge=0.0, le=0.3,
        description="half-range of an episode's height scale (about the floor)",
    )
    lost: float = Field(
        0.0, ge=0.0, le=10.0,
        description="chance per second that a controller loses tracking and is held at its "
        "last pose (as live sessions hold it); 0: never",
    )
    lost_seconds: float = Field(
        0.5, gt=0.0, le=5.0, description="longest loss of tracking, s (each uniform up to it)"
    )


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
    devices: Literal["person", "character"] = Field(
        "character",
        description="the size of the person whose devices a policy reads: 'character' scales "
        "each clip (path and bones) to the size its reference is retargeted at, so headset, "
        "controllers, headset views and estimator targets sit on the reference's body "
        "whoever performed the clip (live streams are scaled by the user's height, calibrated "
        "on the first headset pose); 'person' keeps the performer's size, so on a performer "
        "shorter or taller than the character the devices drift from the reference with "
        "every metre walked (what a run recorded before this field meant: its lock is read so)",
    )
    root_assist: RootAssistOptions | None = Field(
        None,
        description="training only: a root force/torque toward the reference, annealed to "
        "zero over anneal_steps (null: none); e.g. {strength: 1, anneal_steps: 3000000}",
    )
    ground_feet: bool = Field(
        False,
        description="put the reference's stance feet on the floor: each frame's root height "
        "corrected so the foot the performer has down touches the floor "
        "(retarget.character.grounding); for characters whose legs are not proportioned like "
        "a person's (the Dino's stance feet float 3-7 cm otherwise); false: the paper's rough "
        "retargeting as it is",
    )
    hinge_elbows: bool = Field(
        True,
        description="retarget each clip with its elbows rewritten as hinges "
        "(retarget.motion.hinge_elbows: the elbow's twist and sideways swing moved into the "
        "shoulder and wrist, the body's pose unchanged), so a character's hinged elbow bends "
        "the forearm where the person's went; false: the bend angle alone, as runs recorded "
        "before this field did (hands 12-33 cm from the person's controllers on Bandai Namco "
        "clips, 9-10 with it)",
    )
    idle_starts: float = Field(
        0.0, ge=0.0, le=1.0,
        description="share of training episodes that start standing in the character's idle "
        "pose (where live sessions start) at frame 0 of a clip that sets off from rest "
        "(motions.rest_ends), instead of in the reference's pose; 0: none",
    )
    device_noise: DeviceNoiseOptions | None = Field(
        None,
        description="training only: each episode's headset and controllers sit higher or lower "
        "(a vertical offset and a height scale drawn per episode), so a device-driven policy "
        "does not depend on a calibration exact to the centimetre, and controllers that lose "
        "tracking now and then (null: exact devices); e.g. {height: 0.05, scale: 0.03, "
        "lost: 0.5}",
    )
