"""Where the CLI writes: results to stdout, warnings and errors to stderr (rich, no tracebacks)."""

from __future__ import annotations

import os
import sys

from rich.console import Console
from rich.markup import escape

# Piped or redirected output (logs, CI) gets no terminal width: rich would squeeze the wide
# metric tables into 80 columns of ellipses. Such output is read in files, so give it room.
_WIDTH = None if sys.stdout.isatty() or "COLUMNS" in os.environ else 240
out = Console(highlight=False, soft_wrap=True, width=_WIDTH)
err = Console(stderr=True, highlight=False, soft_wrap=True)


def error(message: str) -> None:
    """Print a user error; the message is plain text (``[a, b]`` in it is not rich markup)."""
    err.print(f"[bold red]error:[/] {escape(message)}", markup=True)


def warning(message: str) -> None:
    """Print a warning; the message is plain text, like :func:`error`'s."""
    err.print(f"[yellow]warning:[/] {escape(message)}", markup=True)
