"""Where the CLI writes: results to stdout, warnings and errors to stderr (rich, no tracebacks)."""

from __future__ import annotations

from rich.console import Console

out = Console(highlight=False, soft_wrap=True)
err = Console(stderr=True, highlight=False, soft_wrap=True)


def error(message: str) -> None:
    err.print(f"[bold red]error:[/] {message}", markup=True)


def warning(message: str) -> None:
    err.print(f"[yellow]warning:[/] {message}", markup=True)
