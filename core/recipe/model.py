"""The structure of a recipe (phase 1 of validation: shape only, plugin parameters untyped).

A recipe names one component per slot (``character``, ``scene``, ``algorithm``), lists of
components (``sensors``, ``observers``) and named tables (``rewards``, ``terminations``). Each
component is ``{type: NAME, ...params}`` or just ``NAME``; parameters are validated against the
plugin's own ``Config`` in phase 2 (:mod:`retarget.recipe.resolve`).
"""

from __future__ import annotations

from typing import Annotated, Any

from pydantic import BaseModel, ConfigDict, Field, field_validator, model_validator

from retarget.settings.env import EnvOptions
from retarget.settings.sim import SimSettings


class Strict(BaseModel):
    model_config = ConfigDict(extra="forbid", allow_inf_nan=False)


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
    include: list[Annotated[str, Field(min_length=1, max_length=200)]] = Field(
        default_factory=list, max_length=100,
        description="only files whose name matches one of these shell patterns (all if empty)",
    )
    exclude: list[Annotated[str, Field(min_length=1, max_length=200)]] = Field(
        default_factory=list, max_length=100,
        description="leave out files whose name matches one of these patterns (a held-out "
        "style: ['*_normal_*'])",
    )
    rest_ends: bool = Field(
        False,
        description="also train on each moving clip set off from standing still and slowed to "
        "a stop (its ends time-warped, retarget.motion.rest_ends): takes cut mid-stride have "
        "neither, and a live user does both",
    )
    mirror: bool = Field(
        False,
        description="also train on each clip mirrored left to right (retarget.motion.mirror): "
        "twice the motion at no cost, and a performer's own asymmetries (a favoured side, a "
        "limp) are no longer all a policy has seen of a motion",
    )
    level_feet: bool = Field(
        True,
        description="turn each foot's frame level where it is planted (retarget.motion."
        "level_feet): a file's ankle-to-toe bone is not the sole, and a character trained on "
        "it stands on tiptoe (Bandai Namco: 19 degrees) or on its heels",
    )
    weights: dict[
        Annotated[str, Field(min_length=1, max_length=200)],
        Annotated[float, Field(ge=0.0, le=1000.0, allow_inf_nan=False)],
    ] = Field(
        default_factory=dict, max_length=100,
        description="how often clips are drawn in training: shell patterns on the file name "
        "-> weight (e.g. {'*_run_*': 3}: runs three times as likely); a clip matching several "
        "takes their product, one matching none keeps 1; a pattern matching no clip is an error",
    )


class Recipe(Strict):
    """A complete, declarative description of one training or evaluation setup."""

    name: str | None = Field(
        None,
        description="run name (defaults to character-sensors): one path component of letters, "
        "digits, '.', '_' and '-', so a run is always written inside the runs directory",
        pattern=r"^[A-Za-z0-9._-]{1,100}$",
    )
    extends: str | None = Field(
        None,
        description="the recipe this one is laid over: a packaged name or a file; absent: the "
        "packaged default for its character; null: stand-alone (resolved recipes say null)",
    )
    seed: int = Field(0, ge=0, le=2**63 - 1, description="random seed of the run")
    character: ComponentRef
    scene: ComponentRef | None = None
    sensors: list[ComponentRef] = Field(default_factory=list)
    observers: list[ComponentRef] = Field(default_factory=list)
    rewards: dict[str, ComponentRef] = Field(default_factory=dict)
    terminations: dict[str, ComponentRef] = Field(default_factory=dict)
    algorithm: ComponentRef | None = None
    callbacks: list[ComponentRef] = Field(
        default_factory=list, max_length=16,
        description="training callbacks (loggers) told of every iteration and checkpoint",
    )
    motions: MotionsSection = Field(default_factory=MotionsSection)
    sim: SimSettings = Field(default_factory=SimSettings)
    env: EnvOptions = Field(default_factory=EnvOptions)

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
    "callbacks": "callback",
}
"""Recipe field -> plugin kind of the components it holds."""
