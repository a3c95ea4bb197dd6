"""The two things every plugin has: a ``name`` and a strict, frozen pydantic ``Config``.

Plugins are classes, registered through hooks (``retarget.registry.hookspecs``). Configuration is
validated when a recipe is loaded, before anything expensive is built, so that a typo fails in
the first second with the file, field and plugin named, rather than after an hour of training.
"""

from __future__ import annotations

import re
from abc import ABC
from typing import Any, ClassVar, Generic, cast, get_args, get_origin

from pydantic import BaseModel, ConfigDict
from typing_extensions import TypeVar

NAME_RE = re.compile(r"^[a-z][a-z0-9_]*$")


class PluginConfig(BaseModel):
    """Base of every plugin's ``Config``: unknown fields are errors and values are immutable."""

    model_config = ConfigDict(extra="forbid", frozen=True, defer_build=True, allow_inf_nan=False)


ConfigT = TypeVar("ConfigT", bound=PluginConfig, default=PluginConfig)
"""The config type a plugin is parameterised with: ``class Fall(Termination[FallConfig])``."""


def config_argument(cls: type) -> type[PluginConfig] | None:
    """The config class ``cls`` names in its own bases (``Base[FooConfig]``), if any."""
    for base in cls.__dict__.get("__orig_bases__", ()):
        origin = get_origin(base)
        if not (isinstance(origin, type) and issubclass(origin, Plugin)):
            continue
        for arg in get_args(base):
            if isinstance(arg, type) and issubclass(arg, PluginConfig):
                return arg
    return None


class Plugin(ABC, Generic[ConfigT]):
    """Base class of every plugin kind.

    Subclasses set ``name`` (snake_case, unique within the kind) and name their config as the
    base's parameter, ``class Fall(Termination[FallConfig])``: that sets the class's ``Config``
    (what recipes validate against) and types ``self.config`` as ``FallConfig`` for the type
    checker, so a plugin reads its fields without ``isinstance`` checks. Setting ``Config =``
    in the class body still works (``self.config`` is then typed as the kind's base config).
    The class docstring is the user-facing help text shown by ``retarget plugins show KIND NAME``.
    """

    name: ClassVar[str]
    kind: ClassVar[str] = "plugin"
    Config: ClassVar[type[PluginConfig]] = PluginConfig
    requires: ClassVar[tuple[str, ...]] = ()
    """What the character must provide, e.g. ``("site:head", "body_group:feet")``: checked
    when a recipe is resolved, before anything is built."""

    config: ConfigT
    """This instance's validated, frozen config (an instance of ``type(self).Config``)."""

    def __init_subclass__(cls, **kwargs: Any) -> None:
        super().__init_subclass__(**kwargs)
        named = config_argument(cls)
        if named is None:
            return
        own = cls.__dict__.get("Config")
        if own is None:
            cls.Config = named
        elif not (isinstance(own, type) and issubclass(own, named)):
            raise TypeError(
                f"{cls.__module__}.{cls.__qualname__}: Config = {getattr(own, '__name__', own)!s} "
                f"is not the {named.__name__} named in its base; drop one of the two"
            )

    def __init__(self, config: PluginConfig | None = None) -> None:
        if config is None:
            config = self.Config()
        elif not isinstance(config, self.Config):
            config = self.Config.model_validate(
                config.model_dump() if isinstance(config, BaseModel) else config
            )
        self.config = cast(ConfigT, config)

    def __repr__(self) -> str:
        return f"{type(self).__name__}({self.config!r})"

    @classmethod
    def example(cls) -> Plugin[Any]:
        """An instance the contract suite can exercise with nothing outside it: by default
        the default config. A plugin whose config has required fields, or that needs files
        only a user has (a teacher run), returns one that works without them."""
        return cls()

    @classmethod
    def summary(cls) -> str:
        """First line of the docstring: the one-line description in ``retarget plugins``."""
        doc = (cls.__doc__ or "").strip()
        return doc.splitlines()[0] if doc else ""
