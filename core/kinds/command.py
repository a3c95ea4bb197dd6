"""CLI commands contributed by plugins (``retarget <name> ...``)."""

from __future__ import annotations

import argparse
from abc import abstractmethod
from typing import TYPE_CHECKING, ClassVar

from retarget.errors import PluginError
from retarget.kinds.base import ConfigT, Plugin

if TYPE_CHECKING:
    from retarget.kinds.lookup import PluginLookup


class Command(Plugin[ConfigT]):
    """Base class of subcommands: ``add_arguments`` declares flags, ``run`` returns an exit code.

    Raise :class:`retarget.errors.RetargetError` for user errors: the CLI prints it as one line.
    """

    kind: ClassVar[str] = "command"
    help: ClassVar[str] = ""
    registry: PluginLookup | None = None
    """The invocation's plugins, set by :meth:`connect` before :meth:`run`."""

    def add_arguments(self, parser: argparse.ArgumentParser) -> None:
        """Declare this command's arguments on its own subparser."""

    def connect(self, registry: PluginLookup) -> None:
        """Receive the invocation's plugin registry before :meth:`run` (kept as
        ``self.registry``), so a command resolves recipes against the same plugins."""
        self.registry = registry

    def plugins(self) -> PluginLookup:
        """The invocation's registry; a command run without :meth:`connect` is an error
        (it would otherwise load every entry point a second time)."""
        if self.registry is None:
            raise PluginError("run() before connect(registry)", plugin=f"command {self.name}")
        return self.registry

    @abstractmethod
    def run(self, args: argparse.Namespace) -> int: ...
