"""Atomic checkpoints: write a temporary file, flush and fsync it, then rename it into place.

A rename is atomic on POSIX file systems, so a process killed at any moment (even SIGKILL in
the middle of a write) leaves either the previous checkpoint or the new one, never a torn
file. The directory is fsynced too, so the rename itself survives a crash.

Loading never runs code from the file: ``torch.load(weights_only=True)`` unpickles only
tensors, containers, numbers, strings and the few numpy types a checkpoint holds (RNG states,
simulator arrays; :data:`SAFE_GLOBALS`). A crafted file that asks for anything else is refused.
"""

from __future__ import annotations

import os
import pickle
import re
import tempfile
from pathlib import Path
from typing import Any

import numpy as np
import torch

from retarget.errors import RetargetError

SAFE_GLOBALS: list[Any] = [
    np.ndarray,
    np.dtype,
    np._core.multiarray._reconstruct,  # how numpy pickles arrays (data, not code)
    bytes,
    *{type(np.dtype(t)) for t in ("float64", "float32", "int64", "int32", "uint32", "bool")},
]
"""What besides tensors and plain containers a checkpoint may contain."""


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
    except OSError as exc:  # a full disk, a vanished directory: the previous file is intact
        Path(tmp).unlink(missing_ok=True)
        raise RetargetError(
            f"cannot write checkpoint: {exc.strerror or exc}",
            file=str(path),
            hint="the previous checkpoint is intact; free space and resume with --resume",
        ) from exc
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
        with path.open("rb") as handle, torch.serialization.safe_globals(SAFE_GLOBALS):
            state = torch.load(handle, map_location="cpu", weights_only=True)
    except FileNotFoundError:
        raise RetargetError("checkpoint not found", file=str(path)) from None
    except pickle.UnpicklingError as exc:
        found = re.search(r"Unsupported global: GLOBAL (\S+)", str(exc))
        if found is None:
            raise RetargetError("cannot read checkpoint: not a checkpoint file",
                                file=str(path)) from None
        raise RetargetError(
            f"refused: the file asks for '{found.group(1)}', which a checkpoint never holds "
            "(loading it could run code)",
            file=str(path),
            hint="only load checkpoints written by retarget train",
        ) from None
    except Exception as exc:
        raise RetargetError(f"cannot read checkpoint: {exc}", file=str(path)) from None
    if not isinstance(state, dict) or not isinstance(state.get("algorithm"), dict):
        held = type(state).__name__ if not isinstance(state, dict) else "no 'algorithm' state"
        raise RetargetError(f"not a retarget checkpoint (it holds {held})", file=str(path))
    bad = _first_non_finite(state["algorithm"], "algorithm")
    if bad is not None:
        raise RetargetError(
            f"the checkpoint's weights are not finite ({bad} holds NaN or inf)",
            file=str(path),
            hint="resume from an earlier checkpoint of the run (checkpoints/ckpt-*.pt)",
        )
    return state


def _first_non_finite(value: Any, where: str) -> str | None:
    """Dotted path of the first floating tensor holding NaN/inf inside ``value``, else None."""
    if isinstance(value, torch.Tensor):
        if value.is_floating_point() and not bool(torch.isfinite(value).all()):
            return where
        return None
    if isinstance(value, dict):
        items = value.items()
    elif isinstance(value, list | tuple):
        items = enumerate(value)
    else:
        return None
    for key, item in items:
        found = _first_non_finite(item, f"{where}.{key}")
        if found is not None:
            return found
    return None
