"""Position-only captures (``.npy``/``.npz``) -> canonical, floor-aligned, contact-labelled clips.

A ``.npy`` holds ``(frames, joints, 3)`` global positions only, so its joint names and frame
rate must be given (a names file, one per line, and ``fps``); a ``.npz`` may carry them
itself (``positions``, optional ``joints`` and ``fps``; what is given to the reader wins).
Joints map onto the canonical skeleton by :mod:`retarget.motion.position_layouts`, rotations
are fitted by :mod:`retarget.motion.fit_positions`. Every failure is a
:class:`~retarget.errors.MotionError` naming the file and what is missing.
"""

from __future__ import annotations

import zipfile
from collections.abc import Mapping, Sequence
from pathlib import Path

import numpy as np

from retarget.errors import MotionError
from retarget.motion import position_layouts as layouts
from retarget.motion import skeleton as sk
from retarget.motion.canonicalize import UNITS, up_axis_matrix
from retarget.motion.clip import MotionClip
from retarget.motion.contacts import label_contacts
from retarget.motion.fit_positions import clip_from_positions
from retarget.motion.floor import align_floor, foot_points
from retarget.motion.plausible import check_plausible

MAX_JOINTS = 1000
MAX_NAMES_BYTES = 1 << 20


def read_joint_names(path: str | Path) -> list[str]:
    """One joint name per line (blank lines and ``#`` comments ignored)."""
    path = Path(path)
    try:
        if path.stat().st_size > MAX_NAMES_BYTES:
            raise MotionError("joint names file is larger than 1 MiB", file=path)
        text = path.read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError) as exc:
        raise MotionError(f"cannot read the joint names: {exc}", file=path) from None
    names = [ln.split("#", 1)[0].strip() for ln in text.splitlines()]
    names = [n for n in names if n]
    if not names:
        raise MotionError("the joint names file lists no joints", file=path)
    return names


def _load_arrays(path: Path) -> tuple[np.ndarray, list[str] | None, float | None]:
    try:
        if path.suffix.lower() == ".npz":
            with np.load(path, allow_pickle=False) as data:
                if "positions" not in data:
                    raise MotionError(
                        f"no 'positions' array (has {', '.join(data.files) or 'none'})", file=path
                    )
                pos = np.asarray(data["positions"])
                names = [str(n) for n in data["joints"]] if "joints" in data else None
                fps = float(data["fps"]) if "fps" in data else None
        else:
            pos = np.load(path, allow_pickle=False)
            names, fps = None, None
    except (OSError, ValueError, TypeError, EOFError, zipfile.BadZipFile) as exc:
        raise MotionError(f"cannot read positions: {exc}", file=path) from None
    return pos, names, fps


def load_positions(
    path: str | Path,
    *,
    joints: Sequence[str] | None = None,
    fps: float | None = None,
    name_map: Mapping[str, layouts.Target] | None = None,
    units: str = "m",
    up: str = "+z",
) -> MotionClip:
    """Read a position-only capture (see the module docstring)."""
    path = Path(path)
    file = str(path)
    pos, file_names, file_fps = _load_arrays(path)
    if pos.ndim != 3 or pos.shape[2] != 3 or pos.dtype.kind != "f":
        raise MotionError(
            f"positions must be floats (frames, joints, 3), got {pos.dtype} {pos.shape}", file=file
        )
    if pos.shape[0] < 2 or not 0 < pos.shape[1] <= MAX_JOINTS:
        raise MotionError(f"positions {pos.shape}: need >= 2 frames and 1-{MAX_JOINTS} joints",
                          file=file)  # fmt: skip
    names = list(joints) if joints is not None else file_names
    rate = fps if fps is not None else file_fps
    lacking = [what for what, v in (("joint names", names), ("frame rate", rate)) if v is None]
    if lacking:
        raise MotionError(
            f"a position-only capture needs its {' and '.join(lacking)}", file=file,
            hint="give --joints NAMES.txt (one name per line) and --fps RATE, or the recipe "
            "fields motions.format: {type: positions, joints: NAMES.txt, fps: RATE}",
        )  # fmt: skip
    assert names is not None and rate is not None
    if not 0 < rate <= 1000:
        raise MotionError(f"frame rate {rate} is outside 0-1000 Hz", file=file)
    if len(names) != pos.shape[1]:
        raise MotionError(f"{len(names)} joint names for {pos.shape[1]} joints in the array",
                          file=file)  # fmt: skip
    if units not in UNITS:
        raise MotionError(f"unknown unit {units!r}; known: {', '.join(UNITS)}", file=file)
    pos = np.asarray(pos, dtype=np.float64)
    bad = np.argwhere(~np.isfinite(pos).all(-1))
    label, layout, tips_map = layouts.choose(names, name_map, file)
    index = {layouts.bare(n): i for i, n in enumerate(names)}
    used = {index[s] for c in sk.JOINT_NAMES for s in layouts._sources(layout[c])}
    bad = bad[np.isin(bad[:, 1], list(used))] if len(bad) else bad
    if len(bad):
        f, j = bad[0]
        raise MotionError(f"frame {f}: joint '{names[j]}' is not finite ({len(bad)} such "
                          "values in mapped joints)", file=file)  # fmt: skip
    world = pos @ (up_axis_matrix(up).T * UNITS[units])

    def point(target: layouts.Target) -> np.ndarray:
        if isinstance(target, str):
            return world[:, index[target]]
        a, b, w = target
        return (1 - w) * world[:, index[a]] + w * world[:, index[b]]

    canon = np.stack([point(layout[c]) for c in sk.JOINT_NAMES], axis=1)
    tips = {k: world[:, index[v]] for k, v in tips_map.items() if v in index}
    with np.errstate(all="ignore"):
        clip = clip_from_positions(canon, rate, tips, name=path.stem)
    if not (np.isfinite(clip.local_rot).all() and np.isfinite(clip.offsets).all()):
        raise MotionError("motion is degenerate (coincident joints?)", file=file)
    clip = align_floor(clip)
    contacts = label_contacts(foot_points(clip), clip.meta["foot_clearance"], clip.fps)  # type: ignore[arg-type]
    meta = {**clip.meta, "units": units, "up": up, "layout": label}
    clip = clip.with_(contacts=contacts, skeleton=f"positions ({label})", meta=meta, source=path)
    return check_plausible(clip, path)
