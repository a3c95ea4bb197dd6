"""Headset-camera images of a motion library, rendered once and memory-mapped afterwards.

Rendering every camera of a rig for every clip frame costs milliseconds per frame, far too
much per environment step; the images depend only on the reference motion, the rig and the
resolution, so they are rendered once into ``ROWS x C x H x W`` uint8 and stored under a key
made of exactly those inputs (a changed clip, rig or size is a new file, never a stale one).
The cache folder is ``RETARGET_CACHE`` or ``~/.cache/retarget``; training reads the file
memory-mapped, so N environments share one copy.
"""

from __future__ import annotations

import hashlib
import os
import tempfile
from pathlib import Path

import numpy as np

from retarget.motion.camera_rigs import CameraRig

VERSION = 1
"""Bumped when the renderer draws differently, so old images are not reused."""
MAX_BYTES = 8 * 2**30
"""Largest cache file written (8 GiB): more is a size mistake, not a dataset."""


def cache_dir() -> Path:
    root = os.environ.get("RETARGET_CACHE", "").strip()
    return (Path(root) if root else Path.home() / ".cache" / "retarget") / "ego"


def cache_key(
    joints: np.ndarray, headsets: np.ndarray, heights: np.ndarray, rig: CameraRig,
    width: int, height: int,
) -> str:  # fmt: skip
    """Hash of everything the images depend on."""
    h = hashlib.sha256()
    h.update(f"v{VERSION} {width}x{height} ".encode())
    h.update(rig.model_dump_json().encode())
    for array in (joints, headsets, heights):
        h.update(np.ascontiguousarray(array, dtype=np.float32).tobytes())
    return h.hexdigest()[:32]


def ego_images(
    joints: np.ndarray,
    headsets: np.ndarray,
    heights: np.ndarray,
    rig: CameraRig,
    width: int,
    height: int,
    *,
    folder: Path | None = None,
    progress: bool = True,
) -> np.ndarray:
    """Images ``(R, C, H, W)`` uint8 of ``R`` frames: joint positions ``(R, J, 3)``, headset
    poses ``(R, 7)`` and body heights ``(R,)``; read from the cache or rendered into it."""
    from retarget.errors import RetargetError

    folder = folder or cache_dir()
    path = folder / f"{cache_key(joints, headsets, heights, rig, width, height)}.npy"
    if path.exists():
        return np.load(path, mmap_mode="r")
    rows, cams = len(joints), len(rig.cameras)
    size = rows * cams * width * height
    if size > MAX_BYTES:
        raise RetargetError(
            f"the camera images would take {size / 2**30:.1f} GiB (at most "
            f"{MAX_BYTES / 2**30:.0f} GiB)", hint="render at a lower resolution or fewer clips",
        )  # fmt: skip
    folder.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(dir=folder, prefix=".ego.", suffix=".npy")
    os.close(fd)
    try:
        out = np.lib.format.open_memmap(tmp, mode="w+", dtype=np.uint8,
                                        shape=(rows, cams, height, width))  # fmt: skip
        render_into(out, joints, headsets, heights, rig, progress)
        out.flush()
        del out
        os.replace(tmp, path)
    finally:
        Path(tmp).unlink(missing_ok=True)
    return np.load(path, mmap_mode="r")


def render_into(
    out: np.ndarray, joints: np.ndarray, headsets: np.ndarray, heights: np.ndarray,
    rig: CameraRig, progress: bool = True,
) -> None:  # fmt: skip
    """Render frame by frame into ``out`` ``(R, C, H, W)`` (any uint8 array: memory map or
    memory), with a progress bar."""
    from rich.progress import (
        BarColumn,
        MofNCompleteColumn,
        Progress,
        TextColumn,
        TimeRemainingColumn,
    )

    from retarget.render.ego import EgoRenderer

    columns = (TextColumn("[bold]camera images"), BarColumn(), MofNCompleteColumn(),
               TimeRemainingColumn())  # fmt: skip
    with (
        EgoRenderer(rig, out.shape[3], out.shape[2]) as render,
        Progress(*columns, transient=True, disable=not progress) as bar,
    ):
        task = bar.add_task("render", total=len(joints))
        for r in range(len(joints)):
            out[r] = render(joints[r], headsets[r], float(heights[r]))
            bar.advance(task)
