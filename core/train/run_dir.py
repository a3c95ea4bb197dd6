"""Run directories: ``runs/NAME/TIMESTAMP/{recipe.lock.yaml, checkpoints/, tb/, metrics.csv,
videos/}`` with a ``latest`` link per name, so ``runs/dino-hmd/latest`` always means the
newest run of that recipe."""

from __future__ import annotations

import datetime as dt
import os
from pathlib import Path

from retarget.errors import RetargetError

CHECKPOINTS = "checkpoints"
LOCK = "recipe.lock.yaml"


def new_run_dir(root: str | Path, name: str) -> Path:
    """Create ``root/name/TIMESTAMP`` (unique) and point ``root/name/latest`` at it.

    ``name`` is one path component (recipes validate it), so nothing is written outside
    ``root``; anything else is refused here too."""
    if not name or name in {".", ".."} or "/" in name or "\\" in name or "\0" in name:
        raise RetargetError(
            f"run name {name!r} must be one path component (no '/', not '.' or '..')",
            hint="set `name:` in the recipe or --set name=NAME",
        )
    base = Path(root) / name
    base.mkdir(parents=True, exist_ok=True)
    stamp = dt.datetime.now().strftime("%Y%m%d-%H%M%S")
    path = base / stamp
    suffix = 1
    while path.exists():
        suffix += 1
        path = base / f"{stamp}-{suffix}"
    for sub in (CHECKPOINTS, "tb", "videos"):
        (path / sub).mkdir(parents=True)
    latest = base / "latest"
    tmp = base / f".latest-{os.getpid()}"
    if tmp.is_symlink() or tmp.exists():
        tmp.unlink()
    tmp.symlink_to(path.name)
    os.replace(tmp, latest)
    return path


def resolve_run(path: str | Path) -> Path:
    """A run directory from ``runs/NAME/latest``, ``runs/NAME/TIMESTAMP`` or ``runs/NAME``."""
    p = Path(path)
    if (p / "latest").exists() and not (p / LOCK).exists():
        p = p / "latest"
    p = p.resolve()
    if not (p / LOCK).exists():
        raise RetargetError(
            "not a run directory (no recipe.lock.yaml)",
            file=str(path),
            hint="pass runs/NAME/latest or a runs/NAME/TIMESTAMP directory",
        )
    return p


def latest_checkpoint(run: Path) -> Path:
    """The newest checkpoint file of a run."""
    files = sorted((run / CHECKPOINTS).glob("ckpt-*.pt"))
    if not files:
        raise RetargetError("run has no checkpoint yet", file=str(run / CHECKPOINTS))
    return files[-1]


def default_run_name(character: str, sensors: list[str]) -> str:
    return "-".join([character, *sensors]) if sensors else character
