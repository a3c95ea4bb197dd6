"""Errors a user can act on.

Every error here carries *where* the problem is (file, line, dotted field path, plugin) so that
the CLI can print one readable line instead of a traceback. Anything that is not a
``RetargetError`` is a bug in retarget or a plugin and is shown with its traceback.
"""

from __future__ import annotations

from pathlib import Path


class RetargetError(Exception):
    """Base class of errors caused by user input (recipes, files, plugins, data)."""

    def __init__(
        self,
        message: str,
        *,
        file: str | Path | None = None,
        line: int | None = None,
        field: str | None = None,
        plugin: str | None = None,
        hint: str | None = None,
    ) -> None:
        self.message = message
        self.file = str(file) if file is not None else None
        self.line = line
        self.field = field
        self.plugin = plugin
        self.hint = hint
        super().__init__(self.format())

    def format(self) -> str:
        """One human-readable line (plus an optional hint line)."""
        where = []
        if self.file is not None:
            where.append(self.file if self.line is None else f"{self.file}:{self.line}")
        if self.field:
            where.append(f"field '{self.field}'")
        if self.plugin:
            where.append(f"plugin '{self.plugin}'")
        text = (", ".join(where) + ": " if where else "") + self.message
        if self.hint:
            text += f"\n  hint: {self.hint}"
        return text


class RecipeError(RetargetError):
    """A recipe file or override is malformed, names an unknown plugin or has a bad value."""


class PluginError(RetargetError):
    """A plugin failed to load, register, or broke its contract."""


class MotionError(RetargetError):
    """A motion file (BVH, device recording, ...) cannot be read; names the file and line."""


class SimulationError(RetargetError):
    """The physics went non-finite or a model could not be compiled."""


class MissingExtra(RetargetError):
    """An optional feature's packages are not installed; names the extra that installs them."""


def require_extra(extra: str, *modules: str, needed_for: str) -> None:
    """Raise :class:`MissingExtra` before any work starts when one of ``modules`` is missing:
    one message shape for every extra (``pip install 'retarget[EXTRA]'``)."""
    import importlib.util

    missing = []
    for module in modules:
        try:
            found = importlib.util.find_spec(module) is not None
        except (ImportError, ValueError):
            found = False
        if not found:
            missing.append(module)
    if missing:
        raise MissingExtra(
            f"{needed_for} needs {', '.join(missing)}, which is not installed",
            hint=f"pip install 'retarget[{extra}]'",
        )
