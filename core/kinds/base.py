"""The two things every plugin has: a ``name`` and a strict, frozen pydantic ``Config``.

Plugins are classes, registered through hooks (``retarget.registry.hookspecs``). Configuration is
validated when a recipe is loaded, before anything expensive is built, so that a typo fails in
the first second with the file, field and plugin named, rather than after an hour of training.
"""

from __future__ import annotations

import re
from abc import ABC
from typing import ClassVar

from pydantic import BaseModel, ConfigDict

NAME_RE = re.compile(r"^[a-z][a-z0-9_]*$")


class PluginConfig(BaseModel):
    """Base of every plugin's ``Config``: unknown fields are errors and values are immutable."""

    model_config = ConfigDict(extra="forbid", frozen=True, defer_build=True, allow_inf_nan=False)


class Plugin(ABC):
    """Base class of every plugin kind.

    Subclasses set ``name`` (snake_case, unique within the kind) and may nest a ``Config``
    subclass of :class:`PluginConfig`. The class docstring is the user-facing help text shown by
    ``retarget plugins show KIND NAME``.
    """

    name: ClassVar[str]
    kind: ClassVar[str] = "plugin"
    Config: ClassVar[type[PluginConfig]] = PluginConfig
    requires: ClassVar[tuple[str, ...]] = ()
    """What the character must provide, e.g. ``("site:head", "body_group:feet")``: checked
    when a recipe is resolved, before anything is built."""

    def __init__(self, config: PluginConfig | None = None) -> None:
        if config is None:
            config = self.Config()
        elif not isinstance(config, self.Config):
            config = self.Config.model_validate(
                config.model_dump() if isinstance(config, BaseModel) else config
            )
        self.config = config

    def __repr__(self) -> str:
        return f"{type(self).__name__}({self.config!r})"

    @classmethod
    def example(cls) -> Plugin:
        """An instance the contract suite can exercise with nothing outside it: by default
        the default config. A plugin whose config has required fields, or that needs files
        only a user has (a teacher run), returns one that works without them."""
        return cls()

    @classmethod
    def summary(cls) -> str:
        """First line of the docstring: the one-line description in ``retarget plugins``."""
        doc = (cls.__doc__ or "").strip()
        return doc.splitlines()[0] if doc else ""
