"""Where the CLI writes: results to stdout, warnings and errors to stderr (rich, no tracebacks).

``out`` and ``err`` are made on first use, so a command that prints nothing through them (or
``retarget --help``) does not import rich.
"""

from __future__ import annotations

import os
import sys
from functools import cache
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from rich.console import Console

    out: Console
    err: Console


@cache
def _console(stream: str) -> Console:
    from rich.console import Console

    if stream == "err":
        return Console(stderr=True, highlight=False, soft_wrap=True)
    # Piped or redirected output (logs, CI) gets no terminal width: rich would squeeze the wide
    # metric tables into 80 columns of ellipses. Such output is read in files, so give it room.
    width = None if sys.stdout.isatty() or "COLUMNS" in os.environ else 240
    return Console(highlight=False, soft_wrap=True, width=width)


def __getattr__(name: str) -> Any:
    if name in ("out", "err"):
        return _console(name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def error(message: str) -> None:
    """Print a user error; the message is plain text (``[a, b]`` in it is not rich markup)."""
    from rich.markup import escape

    _console("err").print(f"[bold red]error:[/] {escape(message)}", markup=True)


def warning(message: str) -> None:
    """Print a warning; the message is plain text, like :func:`error`'s."""
    from rich.markup import escape

    _console("err").print(f"[yellow]warning:[/] {escape(message)}", markup=True)
