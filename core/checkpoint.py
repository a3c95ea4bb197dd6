"""Atomic checkpoints: write a temporary file, flush and fsync it, then rename it into place.

A rename is atomic on POSIX file systems, so a process killed at any moment (even SIGKILL in
the middle of a write) leaves either the previous checkpoint or the new one, never a torn
file. The directory is fsynced too, so the rename itself survives a crash.
"""

from __future__ import annotations

import os
import tempfile
from pathlib import Path
from typing import Any

import torch

from retarget.errors import RetargetError


def save_checkpoint(path: str | Path, state: dict[str, Any]) -> Path:
    """Write ``state`` (anything ``torch.save`` takes) to ``path`` atomically."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.", suffix=".tmp")
    try:
        with os.fdopen(fd, "wb") as handle:
            torch.save(state, handle)
            handle.flush()
            os.fsync(handle.fileno())
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise
    dir_fd = os.open(path.parent, os.O_RDONLY)
    try:
        os.fsync(dir_fd)
    finally:
        os.close(dir_fd)
    return path


def load_checkpoint(path: str | Path) -> dict[str, Any]:
    """Read a checkpoint; an unreadable file is a :class:`RetargetError` naming it."""
    path = Path(path)
    try:
        with path.open("rb") as handle:
            return torch.load(handle, map_location="cpu", weights_only=False)
    except FileNotFoundError:
        raise RetargetError("checkpoint not found", file=str(path)) from None
    except Exception as exc:
        raise RetargetError(f"cannot read checkpoint: {exc}", file=str(path)) from None
