"""Run directories: ``runs/NAME/TIMESTAMP/{recipe.lock.yaml, checkpoints/, tb/, metrics.csv}``
with a ``latest`` link per name, so ``runs/dino-hmd/latest`` always means the newest run of
that recipe."""

from __future__ import annotations

import datetime as dt
import os
import re
import shutil
from collections.abc import Iterator
from contextlib import contextmanager, suppress
from pathlib import Path

from retarget.errors import RetargetError

CHECKPOINTS = "checkpoints"
LOCK = "recipe.lock.yaml"
CURRENT = "CURRENT"
"""A file in ``checkpoints/`` naming the checkpoint that is the model, where the folder holds
others too: a shipped teacher keeps the older checkpoints its shipped students distilled
from, and a new training run numbers its checkpoints from 1 again, so the highest number is
not the newest."""


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
    suffix = 1
    while True:  # mkdir claims the directory atomically: two runs started at once never share
        path = base / (stamp if suffix == 1 else f"{stamp}-{suffix}")
        try:
            path.mkdir()
            break
        except FileExistsError:
            suffix += 1
    for sub in (CHECKPOINTS, "tb"):
        (path / sub).mkdir(parents=True)
    latest = base / "latest"
    tmp = base / f".latest-{os.getpid()}"
    if tmp.is_symlink() or tmp.exists():
        tmp.unlink()
    tmp.symlink_to(path.name)
    os.replace(tmp, latest)
    return path


@contextmanager
def starting_run(root: str | Path, name: str) -> Iterator[Path]:
    """:func:`new_run_dir` for a run about to start: if the block fails (a clip that cannot be
    read, weights that do not fit), the new directory is removed and ``latest`` points where
    it pointed before, so a failed start leaves no run behind."""
    base = Path(root) / name
    latest = base / "latest"
    previous = os.readlink(latest) if latest.is_symlink() else None
    path = new_run_dir(root, name)
    try:
        yield path
    except BaseException:
        shutil.rmtree(path, ignore_errors=True)
        if previous is not None:
            tmp = base / f".latest-{os.getpid()}"
            tmp.unlink(missing_ok=True)
            tmp.symlink_to(previous)
            os.replace(tmp, latest)
        else:
            latest.unlink(missing_ok=True)
            with suppress(OSError):
                base.rmdir()  # only if nothing else is in it
        raise


def resolve_run(path: str | Path) -> Path:
    """A run directory from ``runs/NAME/latest``, ``runs/NAME/TIMESTAMP``, ``runs/NAME`` or
    ``pretrained:NAME`` (a model shipped in the package, :mod:`retarget.pretrained`)."""
    from retarget import pretrained

    p = pretrained.resolve(path)
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


CKPT = r"ckpt-(\d+)\.pt"
"""A numbered checkpoint's file name; the number is the training iteration it was saved at."""


def run_checkpoints(run: Path) -> list[Path]:
    """The run's numbered checkpoint files (``ckpt-N.pt``), oldest first."""
    files = [f for f in (run / CHECKPOINTS).glob("ckpt-*.pt") if re.fullmatch(CKPT, f.name)]
    return sorted(files, key=checkpoint_iteration)


def checkpoint_iteration(file: Path) -> int:
    """The iteration of a numbered checkpoint file (``ckpt-0000360.pt``: 360)."""
    found = re.fullmatch(CKPT, file.name)
    if found is None:
        raise RetargetError("is not a numbered checkpoint (ckpt-N.pt)", file=str(file))
    return int(found.group(1))


def latest_checkpoint(run: Path) -> Path:
    """The newest checkpoint file of a run: the one ``checkpoints/CURRENT`` names when there
    is one, else the highest numbered."""
    marker = run / CHECKPOINTS / CURRENT
    if marker.is_file():
        name = marker.read_text(encoding="utf-8", errors="replace")[:64].strip()
        if not re.fullmatch(CKPT, name) or not (run / CHECKPOINTS / name).is_file():
            raise RetargetError(
                f"names {name!r}, which is no checkpoint file beside it",
                file=str(marker),
            )
        return run / CHECKPOINTS / name
    files = run_checkpoints(run)
    if not files:
        raise RetargetError("run has no checkpoint yet", file=str(run / CHECKPOINTS))
    return files[-1]


def default_run_name(
    character: str,
    sensors: list[str],
    *,
    recipe: str | None = None,
    scene: str | None = None,
    observers: list[str] | None = None,
    algorithm: str | None = None,
) -> str:
    """What a run is, as its directory name: ``[recipe-]character-sensors[-scene][-observers]
    [-algorithm]``, so runs of different recipes do not share ``runs/NAME``. ``recipe`` is the
    recipe file's name (left out for the packaged default), ``scene`` is left out when flat,
    ``algorithm`` when PPO."""
    parts = [recipe] if recipe else []
    parts += [character, *sensors]
    if scene and scene != "flat":
        parts.append(scene)
    parts += observers or []
    if algorithm and algorithm != "ppo":
        parts.append(algorithm)
    return "-".join(parts)[:100]


class RunLock:
    """An exclusive lock on a run directory while a process trains it: a second ``--resume``
    of a run that is still training is refused instead of interleaving two writers. The lock
    is the kernel's (``flock``), so it vanishes with the process, even after SIGKILL."""

    FILE = ".train.lock"

    def __init__(self, run: Path) -> None:
        self.path = Path(run) / self.FILE
        self.handle = None

    def acquire(self) -> RunLock:
        import fcntl

        handle = self.path.open("a+")
        try:
            fcntl.flock(handle, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            handle.seek(0)
            owner = handle.read().strip() or "another process"
            handle.close()
            raise RetargetError(
                f"this run is being trained by {owner}",
                file=str(self.path.parent),
                hint="wait for it to stop (Ctrl-C there), or train a new run",
            ) from None
        handle.seek(0)
        handle.truncate()
        handle.write(f"pid {os.getpid()}\n")
        handle.flush()
        self.handle = handle
        return self

    def release(self) -> None:
        if self.handle is not None:
            self.handle.close()  # closing drops the flock
            self.handle = None
