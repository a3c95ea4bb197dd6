"""What a plugin may ask of the invocation's plugin set: the lookup protocol.

An algorithm or command is handed the invocation's registry (``connect``) to resolve other
plugins (a teacher's recipe, a motion format). The contract names only this shape, so the
plugin kinds sit below the registry that holds them (:class:`retarget.registry.Registry`
is the implementation)."""

from __future__ import annotations

from typing import Any, Protocol, runtime_checkable


@runtime_checkable
class PluginLookup(Protocol):
    """The registered plugins of one invocation, by kind and name."""

    def names(self, kind: str) -> list[str]:
        """Every registered name of ``kind`` (``character``, ``motion_format``, ...)."""
        ...

    def get(self, kind: str, name: str) -> Any:
        """The entry of ``name`` (its ``cls``, ``kind``, ``name``, ``origin``); an unknown
        name raises :class:`retarget.errors.PluginError` with the choices."""
        ...

    def motion_formats(self) -> dict[str, Any]:
        """One default-configured reader of every registered motion format, by name."""
        ...
