"""The shared reference data (real motion capture, scene recordings) that tests and benchmarks
read from where it lives, never copying it into the project.

``RETARGET_SHARED_DATA`` names the shared data folder (holding ``mocap/`` and ``scenes/``) or
directly a folder of clips; unset, ``../shared/data`` beside the checkout is used.
"""

from __future__ import annotations

import os
from pathlib import Path

from retarget.errors import RetargetError

ENV_VAR = "RETARGET_SHARED_DATA"
_CHECKOUT = Path(__file__).resolve().parents[2]


def shared_data(part: str = "mocap") -> Path:
    """The folder of one part of the shared data (``mocap``, ``scenes/box_climb``, ...)."""
    env = os.environ.get(ENV_VAR, "").strip()
    root = Path(env).expanduser() if env else _CHECKOUT.parent / "shared" / "data"
    return root / part if (root / part).is_dir() or not env else root


def require_clips(folder: Path, suffix: str = ".bvh") -> list[Path]:
    """The ``suffix`` files of ``folder``, or an error saying where they were looked for (so
    a benchmark stops before it starts working, not an hour in)."""
    files = sorted(folder.glob(f"*{suffix}")) if folder.is_dir() else []
    if not files:
        raise RetargetError(
            f"no {suffix} clips in {folder}",
            hint=f"set {ENV_VAR} to the shared data folder (with mocap/ in it)",
        )
    return files
