"""The structure of a recipe (phase 1 of validation: shape only, plugin parameters untyped).

A recipe names one component per slot (``character``, ``scene``, ``algorithm``), lists of
components (``sensors``, ``observers``) and named tables (``rewards``, ``terminations``). Each
component is ``{type: NAME, ...params}`` or just ``NAME``; parameters are validated against the
plugin's own ``Config`` in phase 2 (:mod:`retarget.recipe.resolve`).
"""

from __future__ import annotations

from typing import Any

from pydantic import BaseModel, ConfigDict, Field, field_validator, model_validator

from retarget.sim.actuation import Actuation


class Strict(BaseModel):
    model_config = ConfigDict(extra="forbid")


class ComponentRef(BaseModel):
    """``{type: NAME, ...params}``; the parameters stay untyped until the plugin is known."""

    model_config = ConfigDict(extra="allow")

    type: str = Field(description="registered plugin name (see `retarget plugins`)")

    @model_validator(mode="before")
    @classmethod
    def _shorthand(cls, value: Any) -> Any:
        if isinstance(value, str):
            return {"type": value}
        return value

    @property
    def params(self) -> dict[str, Any]:
        return dict(self.model_extra or {})


class MotionsSection(Strict):
    """Where the human motion comes from; ``path: null`` uses the packaged generated set."""

    path: str | None = Field(
        None, description="file or directory of clips; RETARGET_DATA is used when unset"
    )
    format: ComponentRef | None = Field(
        None, description="motion format plugin; chosen by file suffix when unset"
    )


class SimSection(Strict):
    """Physics timing: ``substeps`` steps of ``1/(control_hz*substeps)`` s per control step."""

    control_hz: float = Field(36.0, gt=0, description="policy rate (the paper uses 36 Hz)")
    substeps: int = Field(10, ge=1, description="physics steps per control step")
    threads: int = Field(0, ge=0, description="physics threads; 0 uses every core")
    actuation: Actuation = Field(
        "torque",
        description="torque: actions scale each joint's torque limit (the paper); pd: actions "
        "are joint-angle targets of torque-limited PD servos (retarget.sim.actuation)",
    )
    pd_saturation: float = Field(
        0.5, gt=0, description="pd: angle error (rad) at which a servo reaches its torque limit"
    )
    pd_damping: float = Field(0.1, ge=0, description="pd: kd = pd_damping * kp (seconds)")


class EnvSection(Strict):
    """The tracking environment's own settings (plugins configure the rest)."""

    num_envs: int = Field(256, ge=1, description="environments stepped together")
    privileged_offsets: list[int] = Field(
        default_factory=lambda: [1, 3, 6],
        description="future reference frames the critic sees (asymmetric critic)",
    )
    reset_lift: float = Field(0.02, ge=0, description="root lift at reset, m")
    groups: dict[str, list[str]] | None = Field(
        None,
        description="observation groups: name -> sources (sensor/observer names, 'proprio', "
        "'privileged'); default actor = sensors + proprio + observers, critic = actor + "
        "privileged",
    )


class Recipe(Strict):
    """A complete, declarative description of one training or evaluation setup."""

    name: str | None = Field(
        None,
        description="run name (defaults to character-sensors): one path component of letters, "
        "digits, '.', '_' and '-', so a run is always written inside the runs directory",
        pattern=r"^[A-Za-z0-9._-]{1,100}$",
    )
    seed: int = 0
    character: ComponentRef
    scene: ComponentRef | None = None
    sensors: list[ComponentRef] = Field(default_factory=list)
    observers: list[ComponentRef] = Field(default_factory=list)
    rewards: dict[str, ComponentRef] = Field(default_factory=dict)
    terminations: dict[str, ComponentRef] = Field(default_factory=dict)
    algorithm: ComponentRef | None = None
    motions: MotionsSection = Field(default_factory=MotionsSection)
    sim: SimSection = Field(default_factory=SimSection)
    env: EnvSection = Field(default_factory=EnvSection)

    @field_validator("name")
    @classmethod
    def _one_component(cls, value: str | None) -> str | None:
        if value in {".", ".."}:
            raise ValueError("a run name cannot be '.' or '..'")
        return value

    @model_validator(mode="before")
    @classmethod
    def _table_types_default_to_key(cls, value: Any) -> Any:
        """In ``rewards``/``terminations`` tables, ``type`` defaults to the entry's key."""
        if not isinstance(value, dict):
            return value
        value = dict(value)
        for table in ("rewards", "terminations"):
            entries = value.get(table)
            if isinstance(entries, dict):
                fixed = {}
                for key, entry in entries.items():
                    if entry is None:
                        entry = {}
                    if isinstance(entry, dict) and "type" not in entry:
                        entry = {"type": key, **entry}
                    fixed[key] = entry
                value[table] = fixed
        return value


SLOTS: dict[str, str] = {
    "character": "character",
    "scene": "scene",
    "sensors": "sensor",
    "observers": "observer",
    "rewards": "reward",
    "terminations": "termination",
    "algorithm": "algorithm",
}
"""Recipe field -> plugin kind of the components it holds."""
