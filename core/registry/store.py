"""Registries of plugin classes, one per kind, with attribution to the providing plugin.

Every registered class records which plugin module (entry point) and which distribution
provided it, so that ``retarget plugins`` can show it and a duplicate name can name both sides.
"""

from __future__ import annotations

import difflib
from collections.abc import Iterator
from dataclasses import dataclass, field

from retarget.errors import PluginError
from retarget.kinds import KINDS, MotionFormat, Plugin
from retarget.kinds.base import NAME_RE


@dataclass(frozen=True)
class Entry:
    """One registered plugin class and where it came from."""

    kind: str
    name: str
    cls: type[Plugin]
    plugin: str  # the entry point (pluggy plugin) name
    distribution: str
    version: str
    aliases: tuple[str, ...] = ()

    @property
    def provider(self) -> str:
        return f"{self.distribution} {self.version} (entry point '{self.plugin}')"


class DuplicateName(PluginError):
    """Two plugins registered the same kind and name (or alias)."""

    def __init__(self, message: str, *, kind: str, name: str, plugin: str, hint: str) -> None:
        super().__init__(message, plugin=plugin, hint=hint)
        self.kind, self.name = kind, name


@dataclass
class Registry:
    """All plugin classes known to one run, keyed by kind and name (aliases resolve too)."""

    entries: dict[str, dict[str, Entry]] = field(
        default_factory=lambda: {kind: {} for kind in KINDS}
    )
    aliases: dict[str, dict[str, str]] = field(default_factory=lambda: {kind: {} for kind in KINDS})
    problems: list[str] = field(default_factory=list)
    clashed: dict[str, set[str]] = field(default_factory=lambda: {kind: set() for kind in KINDS})
    """Names two plugins both registered: neither is used (see :meth:`withdraw`)."""

    def add(self, entry: Entry) -> None:
        """Add ``entry``; a name or alias already taken is an error naming both providers."""
        base = KINDS[entry.kind]
        if not (isinstance(entry.cls, type) and issubclass(entry.cls, base)):
            raise PluginError(
                f"registered {entry.cls!r} as a {entry.kind}, but it is not a subclass of "
                f"retarget.kinds.{base.__name__}",
                plugin=entry.plugin,
            )
        for label in (entry.name, *entry.aliases):
            if not NAME_RE.match(label):
                raise PluginError(
                    f"{entry.kind} name '{label}' of {entry.cls.__name__} is not snake_case",
                    plugin=entry.plugin,
                )
            other = self._lookup(entry.kind, label)
            if other is not None or label in self.clashed[entry.kind]:
                first = other.provider if other is not None else "another plugin"
                raise DuplicateName(
                    f"duplicate {entry.kind} name '{label}': provided by {first} "
                    f"and by {entry.provider}; neither is used",
                    kind=entry.kind,
                    name=label,
                    plugin=entry.plugin,
                    hint="uninstall one of the two distributions, or restrict loading with "
                    "RETARGET_LOAD_PLUGINS",
                )
        self.entries[entry.kind][entry.name] = entry
        for alias in entry.aliases:
            self.aliases[entry.kind][alias] = entry.name

    def owner(self, kind: str, name: str) -> Entry | None:
        """The entry holding ``name`` (a name or alias) of ``kind``, if any."""
        return self._lookup(kind, name)

    def replace(self, entry: Entry) -> None:
        """Put ``entry`` in place of whatever holds its names (a built-in taking back a name
        a third party registered first)."""
        for label in (entry.name, *entry.aliases):
            other = self._lookup(entry.kind, label)
            if other is not None:
                del self.entries[entry.kind][other.name]
                for alias in other.aliases:
                    self.aliases[entry.kind].pop(alias, None)
        self.add(entry)

    def withdraw(self, kind: str, name: str) -> None:
        """Remove ``name`` (and whatever it is an alias of) and refuse it from now on: when two
        plugins claim one name, neither is used, rather than whichever loaded last."""
        entry = self._lookup(kind, name)
        self.clashed[kind].add(name)
        if entry is None:
            return
        del self.entries[kind][entry.name]
        for alias in entry.aliases:
            self.aliases[kind].pop(alias, None)

    def _lookup(self, kind: str, name: str) -> Entry | None:
        table = self.entries[kind]
        if name in table:
            return table[name]
        target = self.aliases[kind].get(name)
        return table[target] if target is not None else None

    def names(self, kind: str) -> list[str]:
        return sorted(self.entries[kind])

    def motion_formats(self) -> dict[str, MotionFormat]:
        """One default-configured reader of every registered motion format, by name: what
        reads a folder of mixed files (each file by the format its suffix names). The one
        place this set is built; the motion layer takes it as an argument."""
        return {
            name: self.entries["motion_format"][name].cls()  # type: ignore[misc]
            for name in self.names("motion_format")
        }

    def get(self, kind: str, name: str) -> Entry:
        """The entry for ``name``; an unknown name raises with the choices and close matches."""
        if kind not in self.entries:
            raise PluginError(f"unknown plugin kind '{kind}'", hint=_choices(list(KINDS), kind))
        entry = self._lookup(kind, name)
        if entry is None:
            known = self.names(kind) + sorted(self.aliases[kind])
            raise PluginError(f"unknown {kind} '{name}'", hint=_choices(known, name))
        return entry

    def __iter__(self) -> Iterator[Entry]:
        for kind in KINDS:
            for name in sorted(self.entries[kind]):
                yield self.entries[kind][name]


def _choices(known: list[str], wanted: str) -> str:
    close = difflib.get_close_matches(wanted, known, n=3, cutoff=0.5)
    text = f"did you mean {' or '.join(repr(c) for c in close)}? " if close else ""
    return text + f"available: {', '.join(known) if known else '(none installed)'}"


def suggest(known: list[str], wanted: str) -> str:
    """A 'did you mean ...? available: ...' hint, shared by registry and recipe errors."""
    return _choices(known, wanted)
